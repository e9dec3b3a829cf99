"""The shipped test series against the model and the closed forms, and the concrete calibration checked by a scan."""
