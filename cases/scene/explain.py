"""Pydantic's validation errors as one line each: the field by its dotted path, what is wrong, what is allowed.

For example ``impact.attack_angle = 120: must be <= 90 (allowed: -90 <= impact.attack_angle <= 90 deg)``.
"""

from __future__ import annotations

import json
import math
import types
import typing
from typing import Any

import annotated_types
from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from fem_loads.resistance import NAMED_LAWS

from .plausible import plausible_of, slip_hint
from .schema import Scene
from .target import LAW_TAGS

__all__ = ["explain"]


def _quoted(text: str, limit: int = 80) -> str:
    """``repr`` of a user's text, shortened to ``limit`` characters."""
    return repr(text) if len(text) <= limit else repr(text[: limit - 3]) + "..."


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
        tagged = [m for m in models if any(typing.get_args(f.annotation) == (part,) for f in m.model_fields.values())]
        if tagged:
            models = tagged
        elif part in LAW_TAGS and LAW_TAGS[part] in models:
            models = [LAW_TAGS[part]]
        elif part != "name" and part not in LAW_TAGS:
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


def _slip_hint(info: Any, given: Any) -> str:
    """The value a number outside its field's hard range probably meant, when its field has a plausible range and
    a usual slip of its unit lands in it (``projectile.diameter = 155``: 0.155, 155 mm), or ''."""
    plausible = plausible_of(info)
    if plausible is None or isinstance(given, bool) or not isinstance(given, (int, float)):
        return ""
    extra = info.json_schema_extra or {}
    return slip_hint(float(given), str(extra.get("unit", "")), plausible.low, plausible.high)


def _show(value: Any) -> str:
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    text = repr(value) if isinstance(value, str) else json.dumps(value, default=str)
    return text if len(text) <= 60 else text[:57] + "..."


def _explain_one(error: ErrorDetails) -> str:
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
        known = sorted({k for m in parent_models for k in m.model_fields})
        return f"{name}: unknown key (allowed here: {', '.join(known)})"
    if kind == "missing":
        return f"{name}: missing (required)"
    if kind == "implausible":  # a value outside its plausible range (.plausible), named by its model
        where = ctx["field"] if name == "scene" else f"{name}.{ctx['field']}"
        return f"{where} = {ctx['shown']}: {ctx['text']}"
    if kind in ("union_tag_not_found", "union_tag_invalid"):
        tags = ", ".join(_tags(_field_at(loc)[1]))
        if kind == "union_tag_not_found":
            return f"{name}: needs shape (allowed: shape = {tags})"
        return f"{name}.shape = {_show(ctx.get('tag'))}: unknown shape (allowed: {tags})"
    if kind in ("model_type", "model_attributes_type", "dict_type"):
        if loc and loc[-1] in LAW_TAGS:
            return (
                f"{name} = {_show(given)}: must be a law (allowed: a name, {', '.join(sorted(NAMED_LAWS))};"
                " a table of A, sigma_0, B, rho_0; model = polynomial (c0, c1, c2), power (c0, c, n),"
                " locking_cavity_expansion (sigma_0, rho_0, locking_strain) or concrete (compressive_strength,"
                " density); or function = 'file.py:name')"
            )
        models = _field_at(loc)[1]
        keys = ", ".join(sorted({k for m in models for k in m.model_fields}))
        return f"{name} = {_show(given)}: must be a table (allowed: a table of {keys})"
    bounds = {
        "greater_than": "> {gt}",
        "greater_than_equal": ">= {ge}",
        "less_than": "< {lt}",
        "less_than_equal": "<= {le}",
    }
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
    if kind in bounds and (hint := _slip_hint(info, given)):
        suffix += f"; {hint}"
    if kind == "value_error" and not loc:
        return rule  # a rule across sections names its fields itself
    if kind == "value_error" or isinstance(given, dict):
        return f"{name}: {rule}{suffix}"
    return f"{name} = {_show(given)}: {rule}{suffix}"


def _tags(models: list[type[BaseModel]]) -> list[str]:
    """The ``shape`` values the models of a tagged union accept, quoted."""
    return [
        repr(arg)
        for m in models
        if "shape" in m.model_fields
        for arg in typing.get_args(m.model_fields["shape"].annotation)
    ]


def explain(exc: ValidationError) -> str:
    """Every error of ``exc`` as one clause, joined by semicolons (one line)."""
    return "; ".join(_explain_one(e) for e in exc.errors(include_url=False))
