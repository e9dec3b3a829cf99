"""The shared ending of the docs' study scripts: compute the study (or read its record back), keep the record,
draw its figures, print its tables.

``python -m docs.SUB.SCRIPT`` computes; ``python -m docs.SUB.SCRIPT --from-json`` prints the tables again from
the record beside the script, without running anything.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path

from cases.run import atomic_write_text


def study_main(
    record_path: Path,
    compute: Callable[[], dict],
    draw: Callable[[dict], None],
    report: Callable[[dict], None],
    argv: list[str] | None = None,
) -> None:
    """Run ``compute`` and keep its record in ``record_path`` (JSON, atomically) and its figures (``draw``), or with
    ``--from-json`` read the record back; then ``report`` it."""
    argv = sys.argv[1:] if argv is None else argv
    if argv == ["--from-json"]:
        record = json.loads(Path(record_path).read_text())
    else:
        record = compute()
        atomic_write_text(record_path, json.dumps(record, indent=1) + "\n")
        draw(record)
    report(record)
