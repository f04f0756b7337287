"""Writing recordings: the McapSink, its lean chunked writer, channels and write failures."""
