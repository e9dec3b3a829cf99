"""Load scenes from TOML, apply ``--set`` overrides, and explain what is wrong.

Every problem ends in a :class:`SceneError` whose message names the field by
its dotted path and says what is allowed, e.g.
``impact.attack_angle = 120: must be <= 90 (allowed: -90 <= impact.attack_angle <= 90 deg)``.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import tomllib
import types
import typing
from pathlib import Path
from typing import Any

import annotated_types
from pydantic import BaseModel, ValidationError

from fem_loads.resistance import NAMED_LAWS

from .schema import LawSpec, MaterialLawSpec, Scene

__all__ = ["SceneError", "load_scene", "scene_from_dict", "apply_overrides", "parse_override",
           "scene_key", "read_toml", "one_line", "MAX_SCENE_BYTES"]

MAX_SCENE_BYTES = 1 << 20  # a scene is a few hundred bytes; anything past 1 MiB is not one


def one_line(text: str) -> str:
    """``text`` with every control character (newline, escape, ...) shown as an escape, so it prints as one line."""
    return "".join(ch if ch.isprintable() or ch == " " else ascii(ch)[1:-1] for ch in str(text))


class SceneError(ValueError):
    """A scene that cannot be used; the message is one line meant for the user."""

    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))


def _quoted(text: str, limit: int = 80) -> str:
    """``repr`` of a user's text, shortened to ``limit`` characters."""
    return repr(text) if len(text) <= limit else repr(text[: limit - 3]) + "..."


def read_toml(path: str | Path) -> dict[str, Any]:
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
    return _toml(text, f"{path}: not valid TOML")


def _toml(text: str, what: str) -> dict[str, Any]:
    """``tomllib.loads`` with its other failures (nesting, 4300-digit integers) as :class:`SceneError`."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{what} ({exc})") from None
    except RecursionError:
        raise SceneError(f"{what} (arrays or tables nested too deeply)") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise SceneError(f"{what} ({exc})") from None


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split ``key.path=value``; the value is read as a TOML value, else as a string."""
    if "=" not in text:
        raise SceneError(f"--set {_quoted(text)}: expected KEY=VALUE, e.g. impact.speed=1120")
    key, raw = text.split("=", 1)
    path = key.strip().split(".")
    if not all(part.strip() and part.replace("_", "").isalnum() for part in path):
        raise SceneError(f"--set {_quoted(text)}: the key must be a dotted path of names, e.g. impact.speed")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"value = {raw}")["value"]
    except tomllib.TOMLDecodeError:
        value = raw  # a bare word such as softer_soil
    except (RecursionError, ValueError):
        raise SceneError(f"--set {_quoted(text)}: the value is not readable (arrays nested too deeply,"
                         " or an integer of more than 4300 digits)") from None
    return [part.strip() for part in path], value


def apply_overrides(data: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """A copy of ``data`` with each ``key.path=value`` of ``overrides`` set."""
    try:
        data = copy.deepcopy(data)
    except RecursionError:
        raise SceneError("scene: arrays or tables nested too deeply") from None
    for text in overrides:
        path, value = parse_override(text)
        node = data
        for depth, part in enumerate(path[:-1]):
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                where = ".".join(path[: depth + 1])
                raise SceneError(f"--set {_quoted(text)}: {where} is a value, not a table"
                                 f" (the key must stop at {where})")
            node = child
        node[path[-1]] = value
    return data


def scene_from_dict(data: dict[str, Any], source: str = "scene") -> Scene:
    """Validate a scene given as nested dictionaries."""
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        try:
            explained = _explain(exc)
        except RecursionError:
            explained = "arrays or tables nested too deeply"
        raise SceneError(f"{source}: " + explained) from None
    except RecursionError:
        raise SceneError(f"{source}: arrays or tables nested too deeply") from None


def load_scene(path: str | Path, overrides: list[str] | None = None) -> Scene:
    """Load and validate a TOML scene, with optional ``key.path=value`` overrides."""
    data = apply_overrides(read_toml(path), overrides or [])
    return scene_from_dict(data, str(path))


def scene_key(scene: Scene) -> str:
    """A digest of the fully resolved scene (defaults filled in)."""
    text = json.dumps(scene.model_dump(mode="json"), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


# ---------------------------------------------------------------------------
# error messages


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    """The pydantic models an annotation may hold (through Optional, unions, Annotated)."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _models_in(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _models_in(arg)]
    if origin in (list, tuple):
        return [m for arg in typing.get_args(annotation) for m in _models_in(arg)]
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return []


_LAW_TAGS = {"coefficients": LawSpec, "material": MaterialLawSpec}  # the tags of schema.LawChoice


def _field_at(loc: tuple) -> tuple[Any, list[type[BaseModel]], str]:
    """The FieldInfo at an error location, the models in play there, and the dotted path.

    Union tags (``ogive``, ``coefficients``) in the location are skipped, so the
    path names the field as a scene file spells it.
    """
    models: list[type[BaseModel]] = [Scene]
    info = None
    path: list[str] = []
    for part in loc:
        if isinstance(part, int):
            path.append(str(part))
            continue
        owners = [m for m in models if part in m.model_fields]
        if owners:
            info = owners[0].model_fields[part]
            models = _models_in(info.annotation)
            path.append(part)
            continue
        # a union tag narrows to the member it names; anything else is an unknown key
        tagged = [m for m in models if any(
            typing.get_args(f.annotation) == (part,) for f in m.model_fields.values())]
        if tagged:
            models = tagged
        elif part in _LAW_TAGS and _LAW_TAGS[part] in models:
            models = [_LAW_TAGS[part]]
        elif part not in ("name", "coefficients", "material"):
            path.append(part if part.isidentifier() else _quoted(part, 40))  # an unknown key, as written
    return info, models, ".".join(path) or "scene"


def _allowed_range(info: Any, name: str) -> str:
    """``lo <= name <= hi unit`` from a field's constraints, or ''."""
    lower = upper = ""
    for item in getattr(info, "metadata", []):
        if isinstance(item, annotated_types.Ge):
            lower = f"{item.ge:g} <= "
        elif isinstance(item, annotated_types.Gt):
            lower = f"{item.gt:g} < "
        elif isinstance(item, annotated_types.Le):
            upper = f" <= {item.le:g}"
        elif isinstance(item, annotated_types.Lt):
            upper = f" < {item.lt:g}"
    if not (lower or upper):
        return ""
    extra = info.json_schema_extra or {}
    unit = f" {extra['unit']}" if extra.get("unit") else ""
    return f"{lower}{name}{upper}{unit}"


def _show(value: Any) -> str:
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    text = repr(value) if isinstance(value, str) else json.dumps(value, default=str)
    return text if len(text) <= 60 else text[:57] + "..."


def _explain_one(error: dict) -> str:
    loc = tuple(error["loc"])
    info, _, name = _field_at(loc)
    kind = error["type"]
    ctx = error.get("ctx", {})
    given = error.get("input")
    if kind == "extra_forbidden":
        _, parent_models, parent = _field_at(loc[:-1])
        key = str(loc[-1])
        # the key as written, even when it spells a union tag such as "name"
        name = ".".join(([] if parent == "scene" else [parent]) + [key if key.isidentifier() else _quoted(key, 40)])
        allowed = sorted({k for m in parent_models for k in m.model_fields})
        return f"{name}: unknown key (allowed here: {', '.join(allowed)})"
    if kind == "missing":
        return f"{name}: missing (required)"
    if kind in ("union_tag_not_found", "union_tag_invalid"):
        tags = ", ".join(_tags(_field_at(loc)[1]))
        if kind == "union_tag_not_found":
            return f"{name}: needs shape (allowed: shape = {tags})"
        return f"{name}.shape = {_show(ctx.get('tag'))}: unknown shape (allowed: {tags})"
    if kind in ("model_type", "model_attributes_type", "dict_type"):
        if loc and loc[-1] in _LAW_TAGS:
            return (f"{name} = {_show(given)}: must be a law (allowed: a name, {', '.join(sorted(NAMED_LAWS))};"
                    " a table of A, sigma_0, B, rho_0; or a table of model, sigma_0, rho_0, locking_strain)")
        models = _field_at(loc)[1]
        keys = ", ".join(sorted({k for m in models for k in m.model_fields}))
        return f"{name} = {_show(given)}: must be a table (allowed: a table of {keys})"
    bounds = {"greater_than": "> {gt}", "greater_than_equal": ">= {ge}",
              "less_than": "< {lt}", "less_than_equal": "<= {le}"}
    if kind in bounds:
        rule = "must be " + bounds[kind].format(**{k: f"{v:g}" for k, v in ctx.items()})
    elif kind == "finite_number":
        rule = "must be a finite number"
    elif kind == "value_error":
        rule = str(ctx.get("error", error["msg"]))
    else:
        rule = error["msg"][0].lower() + error["msg"][1:]
    allowed = _allowed_range(info, name)
    suffix = f" (allowed: {allowed})" if allowed and kind not in ("value_error",) else ""
    if kind == "value_error" and not loc:
        return rule  # a rule across sections names its fields itself
    if kind == "value_error" or isinstance(given, dict):
        return f"{name}: {rule}{suffix}"
    return f"{name} = {_show(given)}: {rule}{suffix}"


def _tags(models: list[type[BaseModel]]) -> list[str]:
    """The ``shape`` values the models of a tagged union accept, quoted."""
    return [repr(arg) for m in models if "shape" in m.model_fields
            for arg in typing.get_args(m.model_fields["shape"].annotation)]


def _explain(exc: ValidationError) -> str:
    return "; ".join(_explain_one(e) for e in exc.errors(include_url=False))
