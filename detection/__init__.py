"""visland.detection stage (see the module list in its README section)."""
