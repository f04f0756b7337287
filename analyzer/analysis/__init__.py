"""Did the gimbal obey? Commands compared with the attitude feedback that follows (sans-IO)."""
