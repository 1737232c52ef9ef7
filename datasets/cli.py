"""Command-line registration of the visland.datasets stage (light: no heavy imports here)."""


def register(subparsers):
    """Add this stage's commands to the visland parser."""
