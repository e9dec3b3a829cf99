"""The timings of docs/performance.md: kernels, one load evaluation, scaling and start-up."""
