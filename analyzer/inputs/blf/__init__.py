"""Vector BLF files read by this tool: file header, log containers, every object header version."""
