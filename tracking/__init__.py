"""visland.tracking stage (see the module list in its README section)."""
