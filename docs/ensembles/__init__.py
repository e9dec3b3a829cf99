"""The ensemble study of docs/ensembles.md: the probability of instability against the impact speed."""
