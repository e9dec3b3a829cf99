"""The characteristic speeds measured on full runs: what makes a run unstable, the critical impact velocity and the
convergent velocity, the ballistic limit, the reduced model's guide of their searches, and maps of them over
scene inputs."""
