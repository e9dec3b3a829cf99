"""The calibrations of docs/calibration.md: the soil fitted to the measured shots, the family's interior to #3."""
