"""The ensemble study of docs/evidence-ensembles.md: the probability of instability against the impact speed."""
