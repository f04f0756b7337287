"""Coverage-guided fuzzing (atheris) of all that reads untrusted bytes: ``python -m fuzz``."""
