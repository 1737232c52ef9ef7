"""Shared pytest configuration: headless OpenGL for any test that renders."""
import os

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
