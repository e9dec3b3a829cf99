"""The tutorial's scene and the command that shows its output (docs/tutorial.md)."""
