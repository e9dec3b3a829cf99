"""A test series: measured shots, one a row of a CSV file, each a scene with its own keys set.

The file's columns (docs/validation.md, "Test series")::

    label,group,scene,impact.speed,projectile.mass,measured.depth,sigma.depth
    v405,51 MPa,forrestal1996_concrete,405,1.608,0.370,5%

* ``scene``: a scene file, its path relative to the CSV's folder, or a shipped scene's name;
* any dotted scene key: set on that shot as ``--set`` would set it (an empty cell sets nothing);
* ``measured.QUANTITY``: a measured quantity of the run's summary (:data:`RUN_QUANTITIES`, SI units; an
  empty cell: not measured on that shot, but every shot measures something);
* ``sigma.QUANTITY``: its standard deviation, absolute or relative with ``%`` (``5%``);
* ``label`` and ``group``: optional (default ``row N`` and the scene's name).

Lines that start with ``#`` are comments (a series' source goes there).  The whole file is read and
every shot's scene validated before anything runs; the first bad cell ends the reading in one line that
names the row, its line in the file and the column.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ... import SCENE_DIR, SHIPPED_SCENES
from ...run import convergence_speed
from ...scene import InputError, Overrides, Scene, apply_overrides, dotted_key, parse_override, read_scene_data
from ..engine.sweep import Sweep, Variation

if TYPE_CHECKING:
    from ..engine.sweep import SweepResult

__all__ = [
    "Measurement",
    "Shot",
    "Series",
    "read_series",
    "parse_series",
    "run_value",
    "finite_number",
    "RUN_QUANTITIES",
    "SERIES_DIR",
    "SHIPPED_SERIES",
]

#: quantities of one run (its summary, and the convergence speed of its history)
RUN_QUANTITIES = (
    "depth",
    "path_length",
    "final_time",
    "final_speed",
    "max_attack_angle",
    "final_attack_angle",
    "axis_angle_change",
    "convergence_speed",
    "mass",
    "centre_of_mass_from_tip",
    "axial_inertia",
    "transverse_inertia",
)
SERIES_DIR = SCENE_DIR / "series"
SHIPPED_SERIES = sorted(p.stem for p in SERIES_DIR.glob("*.csv"))
#: the columns that are not scene keys
RESERVED = ("label", "group", "scene")
MAX_SHOTS = 10_000
MAX_BYTES = 16 << 20


@dataclass(frozen=True)
class Measurement:
    """``quantity`` measured as ``value`` (SI units) with standard deviation ``sigma`` (absolute; None: not given)."""

    quantity: str
    value: float
    sigma: float | None


@dataclass(frozen=True)
class Shot:
    """One row of a series: its scene file with ``values`` (dotted key -> value) set, and what was measured."""

    label: str
    group: str
    scene: str
    values: dict[str, Any]
    measurements: tuple[Measurement, ...]
    line: int = 0

    def measured(self, quantity: str) -> Measurement | None:
        return next((m for m in self.measurements if m.quantity == quantity), None)


@dataclass
class Series:
    """The shots of a series file, in its order.

    Parameters
    ----------
    source : str
        Where the shots came from (the file), for messages and reports.
    shots : list of Shot
    columns : list of str
        The scene keys the file sets per shot, in its column order.
    """

    source: str
    shots: list[Shot]
    columns: list[str] = field(default_factory=list)

    @property
    def quantities(self) -> list[str]:
        """The measured quantities, in the order they first appear."""
        return list(dict.fromkeys(m.quantity for shot in self.shots for m in shot.measurements))

    @property
    def labels(self) -> list[str]:
        return [shot.label for shot in self.shots]

    @property
    def groups(self) -> list[str]:
        return list(dict.fromkeys(shot.group for shot in self.shots))

    def subset(self, labels: Sequence[str]) -> Series:
        """The shots with these labels, in the series' order."""
        wanted = set(labels)
        return replace(self, shots=[shot for shot in self.shots if shot.label in wanted])

    def bases(self, overrides: Overrides | None = None) -> dict[str, dict]:
        """Every shot's scene as nested dictionaries with ``overrides`` (``--set``) and then its own values set
        (a column beats ``--set`` for its own shot), keyed by the shot's label."""
        files = {scene: read_scene_data(scene) for scene in dict.fromkeys(shot.scene for shot in self.shots)}
        return {
            shot.label: apply_overrides(
                apply_overrides(files[shot.scene], overrides, shot.scene), shot.values, shot.scene
            )
            for shot in self.shots
        }

    def parts(
        self, overrides: Overrides | None = None, variations: Sequence[Mapping[str, Any]] = ({},)
    ) -> list[tuple[dict, str, Variation]]:
        """Every shot under every variation (``target.law`` of a law comparison, the parameters of a fit), the
        shots varying fastest, as parts of :meth:`Sweep.from_bases <cases.studies.engine.sweep.Sweep.from_bases>`."""
        try:
            bases = self.bases(overrides)
        except InputError as exc:
            raise InputError(f"{self.source}: {exc}") from None
        return [
            (bases[shot.label], shot.scene, Variation(dict(values))) for values in variations for shot in self.shots
        ]

    def sweep(self, overrides: Overrides | None = None, variations: Sequence[Mapping[str, Any]] = ({},)) -> Sweep:
        """:meth:`parts` as one sweep; every scene validated here, before anything runs, and a bad one named
        by its shot."""
        return combined(self, self.parts(overrides, variations))


def combined(series: Series, parts: list[tuple[dict, str, Variation]]) -> Sweep:
    """``Sweep.from_bases(parts)``, whose first ``len(series.shots) * k`` parts are the series' shots: a scene
    that does not validate is named by its shot."""
    try:
        return Sweep.from_bases(parts)
    except InputError as exc:
        index = len(_valid_prefix(parts))
        if index >= len(parts) or not series.shots:
            raise
        shot = series.shots[index % len(series.shots)]
        raise InputError(f"{series.source}: {shot_name(shot)}: {_without_source(str(exc), shot.scene)}") from None


def _valid_prefix(parts: list[tuple[dict, str, Variation]]) -> list[Sweep]:
    """The parts whose scenes validate, up to the first that does not."""
    done = []
    for part in parts:
        try:
            done.append(Sweep.from_bases([part]))
        except InputError:
            break
    return done


def _without_source(message: str, source: str) -> str:
    return message.removeprefix(f"{source}: ")


def shot_name(shot: Shot) -> str:
    """How messages name a shot: its row's line in the file and its label."""
    return f"line {shot.line} ({shot.label})" if shot.line else shot.label


def run_value(result: SweepResult, index: int, quantity: str) -> float | None:
    """``quantity`` of run ``index`` of a sweep: a summary field, or the convergence speed of its history."""
    run = result.runs[index]
    if run.summary is None:
        return None
    value = (
        convergence_speed(result.history(index)) if quantity == "convergence_speed" else getattr(run.summary, quantity)
    )
    return None if value is None or not math.isfinite(value) else float(value)


def _scene_file(text: str, folder: Path, where: str) -> str:
    """A row's ``scene`` cell as a path: a file relative to the series' folder, else a shipped scene's name."""
    if not text:
        raise InputError(f"{where}, column 'scene': empty (give a scene file, or a shipped scene's name)")
    path = folder / text
    if path.is_file():
        return str(path)
    name = text.removesuffix(".toml")
    if name in SHIPPED_SCENES and "/" not in text:
        return str(SCENE_DIR / f"{name}.toml")
    raise InputError(
        f"{where}, column 'scene': {text!r}: no such scene file (relative to {folder}) and no shipped scene"
        f" of that name (shipped: {', '.join(SHIPPED_SCENES)})"
    )


def finite_number(text: str, where: str) -> float:
    """``text`` as a finite float, else an :class:`InputError` naming ``where``."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise InputError(f"{where}: {text!r}: must be a finite number")
    return value


def _sigma(text: str, value: float, where: str) -> float:
    """An absolute sigma from ``text``: a number, or a percentage of ``value``."""
    relative = text.endswith("%")
    sigma = finite_number(text.removesuffix("%").strip(), where)
    if not sigma > 0:
        raise InputError(f"{where}: {text!r}: must be > 0 (a standard deviation, or a percentage with %)")
    if relative:
        if value == 0:
            raise InputError(f"{where}: {text!r}: a relative sigma of a measurement of 0 is 0; give it in SI units")
        return sigma / 100 * abs(value)
    return sigma


def read_series(path: str | os.PathLike[str]) -> Series:
    """The series in a CSV file (or a shipped series' name); every cell and every shot's scene checked.

    Raises
    ------
    InputError
        The first bad cell, in one line naming the row and the column; nothing has run.
    """
    text_path = str(path)
    file = Path(text_path)
    if not file.is_file() and text_path.removesuffix(".csv") in SHIPPED_SERIES and "/" not in text_path:
        file = SERIES_DIR / f"{text_path.removesuffix('.csv')}.csv"
    if not file.is_file():
        shipped = ", ".join(SHIPPED_SERIES)
        raise InputError(f"{text_path}: no such series file (give a CSV file, or a shipped series: {shipped})")
    if file.stat().st_size > MAX_BYTES:
        raise InputError(f"{file}: larger than {MAX_BYTES >> 20} MiB (a series must be smaller; split it)")
    try:
        text = file.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{file}: not readable as UTF-8 text ({type(exc).__name__})") from None
    return parse_series(text, file.parent, str(file))


def parse_series(text: str, folder: Path, source: str = "series") -> Series:
    """The series in CSV ``text``; scene files are found relative to ``folder``.  See :func:`read_series`."""
    lines = [(number, line) for number, line in enumerate(text.splitlines(), start=1)]
    data = [(number, line) for number, line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not data:
        raise InputError(f"{source}: empty (expected a header line, e.g. scene,impact.speed,measured.depth, and a row)")
    if "\x00" in text:
        raise InputError(f"{source}: not a CSV text file (it holds NUL bytes)")
    try:
        rows = list(csv.reader(io.StringIO("\n".join(line for _, line in data))))
    except csv.Error as exc:
        raise InputError(f"{source}: not readable as CSV ({exc})") from None
    header = [cell.strip() for cell in rows[0]]
    numbers = [number for number, _ in data]
    columns, measured, sigmas = _columns(header, source, numbers[0])
    if len(rows) == 1:
        raise InputError(f"{source}: no shots (a header and no rows; give one shot a row)")
    if len(rows) - 1 > MAX_SHOTS:
        raise InputError(f"{source}: {len(rows) - 1} rows (allowed: at most {MAX_SHOTS} shots)")
    shots = []
    for row_number, (line, cells) in enumerate(zip(numbers[1:], rows[1:]), start=1):
        where = f"{source}: row {row_number} (line {line})"
        if len(cells) != len(header):
            raise InputError(f"{where}: {len(cells)} cells for {len(header)} columns")
        cell = dict(zip(header, (c.strip() for c in cells)))
        scene = _scene_file(cell.get("scene", ""), folder, where)
        values: dict[str, Any] = {}
        for key in columns:
            if cell[key]:
                try:
                    values[key] = parse_override(f"{key}={cell[key]}")[1]
                except InputError:
                    raise InputError(f"{where}, column {key!r}: {cell[key]!r:.60}: not a readable value") from None
        measurements = []
        for quantity in measured:
            raw = cell[f"measured.{quantity}"]
            sigma_raw = cell.get(f"sigma.{quantity}", "")
            if not raw:
                if sigma_raw:
                    raise InputError(f"{where}, column 'sigma.{quantity}': a sigma without a measured.{quantity}")
                continue
            value = finite_number(raw, f"{where}, column 'measured.{quantity}'")
            sigma = _sigma(sigma_raw, value, f"{where}, column 'sigma.{quantity}'") if sigma_raw else None
            measurements.append(Measurement(quantity, value, sigma))
        if not measurements:
            raise InputError(f"{where}: nothing measured (fill at least one measured.QUANTITY cell)")
        label = cell.get("label") or f"row {row_number}"
        group = cell.get("group") or Path(scene).stem
        shots.append(Shot(label, group, scene, values, tuple(measurements), line))
    seen: dict[str, Shot] = {}
    for shot in shots:
        if shot.label in seen:
            raise InputError(
                f"{source}: {shot_name(shot)}, column 'label': {shot.label!r} is also the label of line"
                f" {seen[shot.label].line} (each shot needs a label of its own)"
            )
        seen[shot.label] = shot
    for key in columns:
        if not any(key in shot.values for shot in shots):
            raise InputError(f"{source}: column {key!r}: every cell is empty (fill it, or drop the column)")
    series = Series(source, shots, columns)
    series.sweep()  # every shot's scene validated before anything runs
    return series


def _columns(header: list[str], source: str, line: int) -> tuple[list[str], list[str], list[str]]:
    """The header's scene keys, measured quantities and sigma columns; refused in one line when unusable."""
    where = f"{source}: header (line {line})"
    if "scene" not in header:
        raise InputError(f"{where}: no 'scene' column (each shot's scene file or shipped scene's name)")
    duplicated = [name for name in dict.fromkeys(header) if header.count(name) > 1]
    if duplicated:
        raise InputError(f"{where}: column {duplicated[0]!r} appears twice")
    keys: list[str] = []
    measured: list[str] = []
    sigmas: list[str] = []
    for name in header:
        if name in RESERVED:
            continue
        kind, _, quantity = name.partition(".")
        if kind in ("measured", "sigma"):
            if quantity not in RUN_QUANTITIES:
                raise InputError(
                    f"{where}, column {name!r}: unknown quantity {quantity!r} (allowed: {', '.join(RUN_QUANTITIES)})"
                )
            (measured if kind == "measured" else sigmas).append(quantity)
            continue
        if not name:
            raise InputError(f"{where}: a column without a name")
        try:
            path = dotted_key(name, f"{where}, column {name!r}")
            if path[0] not in Scene.model_fields:
                raise InputError(name)
            keys.append(".".join(path))
        except InputError:
            raise InputError(
                f"{where}, column {name!r}: unknown column (allowed: label, group, scene, measured.QUANTITY,"
                " sigma.QUANTITY, or a dotted scene key such as impact.speed)"
            ) from None
    for quantity in sigmas:
        if quantity not in measured:
            raise InputError(f"{where}, column 'sigma.{quantity}': no measured.{quantity} column beside it")
    if not measured:
        raise InputError(
            f"{where}: no measured.QUANTITY column (e.g. measured.depth; allowed: {', '.join(RUN_QUANTITIES)})"
        )
    return keys, measured, sigmas
