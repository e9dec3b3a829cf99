"""The calibrations of docs/evidence-calibration.md: the soil fitted to the measured shots, the interior to #3."""
