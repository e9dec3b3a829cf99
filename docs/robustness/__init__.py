"""The fuzzing table of docs/robustness.md, read off the test module."""
