"""Set-up tooling: warming the caches a first run or study would otherwise fill (``./dev`` runs it).

Nothing imports it.  What it may import is written once, in pyproject.toml's [tool.penetrate.rooms].
"""
