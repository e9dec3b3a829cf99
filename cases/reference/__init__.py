"""Independent references for a normal impact: the closed form and the 1-D integration of the nose along its axis
(no mesh), the truth the physics is tested against and the guide of the ballistic-limit search.

What it may import is written once, in pyproject.toml's [tool.penetrate.rooms].
"""
