"""What the numerics cost and change: accuracy against time over mesh, step and tolerance, and the contact ramp's
and the entry smoothing's effect on a run."""
