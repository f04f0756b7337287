"""Live view in Foxglove: the decoded stream served over the Foxglove WebSocket protocol."""
