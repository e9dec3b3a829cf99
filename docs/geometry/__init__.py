"""The projectiles from files, the non-axisymmetric bodies and the eroded-nose study of docs/evidence-geometry.md."""
