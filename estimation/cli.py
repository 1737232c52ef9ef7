"""Command-line registration of the visland.estimation stage (light: no heavy imports here)."""


def register(subparsers):
    """Add this stage's commands to the visland parser."""
