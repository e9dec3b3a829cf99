"""Read scenes from TOML, apply overrides, validate, and key them.

Overrides are ``(dotted key, value)`` pairs, e.g. ``{"impact.speed": 1120}``,
applied to the scene's nested dictionaries before validation; values are
never passed as text (the command line's ``--set KEY=VALUE`` is read once, by
:func:`parse_override`).  An override replaces what the scene gave: setting one
of a set of alternative keys removes the others the scene file had
(:data:`ALTERNATIVES`, :data:`TAGGED_TABLES`), so ``target.layers`` replaces
``target.law`` and a new ``projectile.nose.shape`` drops the old shape's keys.

Every problem ends in a :class:`~.errors.SceneError` whose message names the
field by its dotted path and says what is allowed.
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import tomllib
import typing
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from .errors import SceneError
from .projectile import NOSE_SPECS
from .schema import Scene

__all__ = [
    "Overrides",
    "load_scene",
    "read_scene_data",
    "anchor_files",
    "scene_from_dict",
    "apply_overrides",
    "parse_override",
    "scene_key",
    "read_toml",
    "read_toml_text",
    "dotted_key",
    "MAX_SCENE_BYTES",
    "ALTERNATIVES",
    "TAGGED_TABLES",
]

MAX_SCENE_BYTES = 1 << 20  # a scene is a few hundred bytes; anything past 1 MiB is not one

Overrides = Mapping[str, Any] | Iterable[tuple[str, Any]]
"""Dotted keys and their values: a mapping or a sequence of pairs (applied in order)."""

# Keys of a table that exclude each other: when overrides set keys of one alternative, the keys of
# the others that the scene gave (and no override set) are removed.  The last entry applies only to
# a homogeneous body (with a counterweight, body_density and mass are both used).
ALTERNATIVES: list[tuple[str, tuple[frozenset[str], ...], str]] = [
    ("target", (frozenset({"law"}), frozenset({"layers"})), ""),
    ("projectile", (frozenset({"centre_of_mass"}), frozenset({"centre_of_mass_ratio"})), ""),
    ("projectile", (frozenset({"mass_properties"}), frozenset({"mass", "centre_of_mass", "centre_of_mass_ratio"})), ""),
    (
        "projectile",
        (
            frozenset({"counterweight.start", "counterweight.end"}),
            frozenset({"mass", "centre_of_mass", "centre_of_mass_ratio"}),
        ),
        "",
    ),
    ("projectile", (frozenset({"mass"}), frozenset({"body_density"})), "no counterweight"),
    (
        "projectile",
        (
            frozenset({"geometry"}),
            frozenset(
                {"diameter", "length", "nose", "interior", "counterweight", "centre_of_mass", "centre_of_mass_ratio"}
            ),
        ),
        "",
    ),
]
# Tables whose tag decides their other keys: a new tag drops the keys the new kind does not have.
TAGGED_TABLES: dict[str, tuple[str, dict[str, frozenset[str]]]] = {
    "projectile.nose": (
        "shape",
        {
            typing.get_args(spec.model_fields["shape"].annotation)[0]: frozenset(spec.model_fields)
            for spec in NOSE_SPECS
        },
    ),
    "effects.friction": (
        "model",
        {
            "none": frozenset({"model", "coefficient"}),
            "coulomb": frozenset({"model", "coefficient"}),
            "capped": frozenset({"model", "coefficient", "cap"}),
        },
    ),
}


def _quoted(text: str, limit: int = 80) -> str:
    """``repr`` of a user's text, shortened to ``limit`` characters."""
    return repr(text) if len(text) <= limit else repr(text[: limit - 3]) + "..."


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML file, turning every failure into a :class:`SceneError`.

    Only data is read: TOML has no expressions, and nothing read is ever evaluated.
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:  # bounded: /dev/zero or a huge file is refused, not read to the end
            raw = f.read(MAX_SCENE_BYTES + 1)
        text = raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else "not UTF-8 text"
        raise SceneError(f"{path}: cannot read the scene file ({reason})") from None
    if len(raw) > MAX_SCENE_BYTES:
        raise SceneError(f"{path}: cannot read the scene file (larger than {MAX_SCENE_BYTES} bytes)")
    return read_toml_text(text, f"{path}: not valid TOML")


def read_toml_text(text: str, what: str) -> dict[str, Any]:
    """``tomllib.loads`` with every failure (nesting, 4300-digit integers) as :class:`SceneError` starting ``what``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{what} ({exc})") from None
    except RecursionError:
        raise SceneError(f"{what} (arrays or tables nested too deeply)") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise SceneError(f"{what} ({exc})") from None


def dotted_key(key: str, what: str) -> list[str]:
    """The parts of a dotted key such as ``impact.speed``; ``what`` names the key's source in the error."""
    path = [part.strip() for part in str(key).strip().split(".")]
    if not all(part and part.replace("_", "").isalnum() for part in path):
        raise SceneError(f"{what}: the key must be a dotted path of names, e.g. impact.speed")
    return path


def parse_override(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` of the command line's ``--set`` as a pair; the value is read as a TOML value, else as a string."""
    if "=" not in text:
        raise SceneError(f"--set {_quoted(text)}: expected KEY=VALUE, e.g. impact.speed=1120")
    key, raw = text.split("=", 1)
    path = dotted_key(key, f"--set {_quoted(text)}")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"value = {raw}")["value"]
    except tomllib.TOMLDecodeError:
        value = raw  # a bare word such as softer_soil
    except (RecursionError, ValueError):
        raise SceneError(
            f"--set {_quoted(text)}: the value is not readable (arrays nested too deeply,"
            " or an integer of more than 4300 digits)"
        ) from None
    return ".".join(path), value


def _pairs(overrides: Overrides | None) -> list[tuple[str, Any]]:
    if overrides is None:
        return []
    pairs = list(overrides.items() if isinstance(overrides, Mapping) else overrides)
    for pair in pairs:
        if not (isinstance(pair, tuple) and len(pair) == 2 and isinstance(pair[0], str)):
            raise SceneError(
                f"overrides: expected (dotted key, value) pairs or a mapping, got {pair!r:.60}"
                " (text such as 'impact.speed=1120' is read by parse_override)"
            )
    return pairs


def apply_overrides(data: dict[str, Any], overrides: Overrides | None, source: str = "scene") -> dict[str, Any]:
    """A copy of ``data`` with each ``(dotted key, value)`` of ``overrides`` set, replacing alternatives.

    ``source`` names the scene in error messages, as :func:`scene_from_dict` does.
    """
    try:
        data = copy.deepcopy(data)
    except RecursionError:
        raise SceneError(f"{source}: arrays or tables nested too deeply") from None
    paths = []
    for key, value in _pairs(overrides):
        path = dotted_key(key, f"{source}: override {_quoted(str(key))}")
        node = data
        for depth, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                where = ".".join(path[: depth + 1])
                raise SceneError(
                    f"{source}: {'.'.join(path)}: {where} is a value, not a table (the key must stop at {where})"
                )
            node = child
        try:
            node[path[-1]] = copy.deepcopy(value)
        except RecursionError:
            raise SceneError(f"{source}: {'.'.join(path)}: arrays or tables nested too deeply") from None
        paths.append(path)
    _drop_replaced(data, paths)
    return data


def _holder(data: dict, path: list[str]) -> dict | None:
    """The dictionary that holds the key ``path`` (None when a table on the way is absent)."""
    for part in path[:-1]:
        child = data.get(part)
        if not isinstance(child, dict):
            return None
        data = child
    return data


def _drop_replaced(data: dict[str, Any], paths: list[list[str]]) -> None:
    """Remove what the overrides replaced: the other alternatives, the keys an old tag had."""

    def present(full: list[str]) -> bool:
        holder = _holder(data, full)
        return holder is not None and full[-1] in holder

    def touched(full: list[str]) -> bool:  # an override set this key, a key inside it, or a table holding it
        return any(p[: len(full)] == full for p in paths) or (present(full) and any(full[: len(p)] == p for p in paths))

    def table_at(dotted: str) -> tuple[list[str], dict | None]:
        base = dotted.split(".")
        if any(base[: len(p)] == p for p in paths):
            return base, None  # replaced as a whole: nothing of the scene file is left in it
        holder = _holder(data, base)
        table = holder.get(base[-1]) if holder is not None else None
        return base, table if isinstance(table, dict) else None

    for dotted, alternatives, condition in ALTERNATIVES:
        base, table = table_at(dotted)
        if table is None or (condition == "no counterweight" and "counterweight" in table):
            continue
        chosen = [alt for alt in alternatives if any(touched(base + key.split(".")) for key in alt)]
        if len(chosen) != 1:
            continue  # none set, or the overrides set two alternatives: validation will say so
        for key in {key for alt in alternatives if alt is not chosen[0] for key in alt}:
            full = base + key.split(".")
            if present(full) and not touched(full):
                holder = _holder(data, full)
                assert holder is not None  # present()
                del holder[full[-1]]
    for dotted, (tag, keys_of) in TAGGED_TABLES.items():
        base, table = table_at(dotted)
        # a tag that is not a known name (a list, say) is left for validation to name
        if (
            table is None
            or base + [tag] not in paths
            or not isinstance(table.get(tag), str)
            or table.get(tag) not in keys_of
        ):
            continue
        for key in [k for k in table if k not in keys_of[table[tag]] and not touched(base + [k])]:
            del table[key]


def scene_from_dict(data: dict[str, Any], source: str = "scene") -> Scene:
    """Validate a scene given as nested dictionaries."""
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        from .explain import explain  # imported on bad input only: a valid scene never needs it

        try:
            explained = explain(exc)
        except RecursionError:
            explained = "arrays or tables nested too deeply"
        raise SceneError(f"{source}: " + explained) from None
    except RecursionError:
        raise SceneError(f"{source}: arrays or tables nested too deeply") from None


def load_scene(path: str | os.PathLike[str], overrides: Overrides | None = None) -> Scene:
    """Load and validate a TOML scene, with optional overrides (dotted key -> value).

    A geometry file or a user law's file named by a relative path in the scene is found beside the scene
    file (one named by an override, relative to the working directory).
    """
    return scene_from_dict(apply_overrides(read_scene_data(path), overrides, str(path)), str(path))


def read_scene_data(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A scene file's nested dictionaries, before overrides and validation, with its files anchored."""
    return anchor_files(read_toml(path), Path(path).parent)


def anchor_files(data: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``data`` with the files it names by relative paths made absolute against ``folder``: the projectile's
    ``geometry.file`` and the ``function`` file of each user law (the target's and its layers').  Changes
    ``data`` in place (a scene file's freshly read tables) and returns it."""

    def anchored(path: str) -> str:
        file = Path(path).expanduser()
        return path if file.is_absolute() else str((folder / file).resolve())

    geometry = data.get("projectile", {}).get("geometry") if isinstance(data.get("projectile"), dict) else None
    if isinstance(geometry, dict) and isinstance(geometry.get("file"), str) and geometry["file"]:
        geometry["file"] = anchored(geometry["file"])
    target = data.get("target")
    laws = []
    if isinstance(target, dict):
        laws.append(target.get("law"))
        if isinstance(target.get("layers"), list):
            laws += [layer.get("law") for layer in target["layers"] if isinstance(layer, dict)]
    for law in laws:
        if isinstance(law, dict) and isinstance(law.get("function"), str) and ":" in law["function"]:
            file, name = law["function"].rsplit(":", 1)
            if file:
                law["function"] = f"{anchored(file)}:{name}"
    return data


def scene_key(scene: Scene) -> str:
    """A digest of the fully resolved scene (defaults filled in)."""
    text = json.dumps(scene.model_dump(mode="json"), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]
