"""Ensembles: sampled impact conditions (distributions and designs), the probability of each outcome with its
interval, and the multi-fidelity ensemble the reduced model sorts."""
