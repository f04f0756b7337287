"""The Python API: the public names ``import analyzer`` gives (see docs/howto/python-api.md)."""
