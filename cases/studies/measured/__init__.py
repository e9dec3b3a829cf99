"""Studies against measurements: test series of shots, their validation, the comparison of resistance laws, and
fits of scene keys to observed quantities."""
