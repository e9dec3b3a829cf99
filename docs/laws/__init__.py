"""The check of every law against the 1-D integration in docs/evidence-laws.md (python -m docs.laws.normal_impact)."""
