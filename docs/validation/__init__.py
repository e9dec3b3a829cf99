"""The shipped test series against the tool and the closed forms, and the concrete calibration with its hold-out
(docs/validation.md)."""
