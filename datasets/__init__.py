"""visland.datasets stage (see the module list in its README section)."""
