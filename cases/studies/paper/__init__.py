"""The paper's instability study reproduced: ``penetrate paper`` and ``penetrate paper --variants``.

Its runs are described as data (:mod:`.plan`), read (:mod:`.analysis`), drawn (:mod:`.figures`)
and reported (:mod:`.report`); :mod:`.study` drives them.
"""

from .plan import FINE_NUMERICS, PAPER_RATIOS, STUDY_NUMERICS, VARIANTS
from .study import reproduce, reproduce_variants

__all__ = ["reproduce", "reproduce_variants", "PAPER_RATIOS", "STUDY_NUMERICS", "FINE_NUMERICS", "VARIANTS"]
