"""The reduced pitch-plane model of a body of revolution (both characteristic speeds in about a second, the guide
of the searches) and the load-only steady-turn boundary."""
