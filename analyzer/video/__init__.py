"""Camera video next to the telemetry: RTSP streams copied into the recording, no re-encoding."""
