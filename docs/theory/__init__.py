"""The reduced pitch-plane model's predictions against the simulator's measurements (docs/evidence-theory.md)."""
