"""The checks (docs/evidence-targets.md) and pictures (docs/targets.md) of slabs, gaps and inclined faces."""
