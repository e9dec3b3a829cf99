"""The reference tables, printed from the code that defines them, so that they cannot drift from it.

``python -m docs.reference.generate scene`` prints every key of a scene file, walked from the scene's pydantic
models (docs/reference/scene.md); ``... cli`` every command of ``penetrate`` and its options, read from the
argparse parser (docs/reference/cli.md); ``... summary`` the fields of a run's summary and the columns of its
``history.csv`` (docs/reference/run-outputs.md).  Each prints markdown on standard output.
"""

from __future__ import annotations

import argparse
import re
import sys
import types
from collections.abc import Callable, Iterable
from typing import Annotated, Any, Literal, TypeGuard, Union, get_args, get_origin

import annotated_types
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

__all__ = ["scene_reference", "cli_reference", "summary_reference", "PAGES", "main"]

#: the bounds a field may carry, and how each reads
BOUNDS = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
#: the plain names of the scalar types of a scene
SCALARS = {bool: "true or false", int: "whole number", float: "number", str: "string"}
#: a history column's meaning, by its name or by its name without the component (``_x``, ``_w``)
HISTORY_MEANING = {
    "time": "time since the tip touched the front face",
    "position": "the centre of mass's position, world frame",
    "velocity": "the centre of mass's velocity, world frame",
    "speed": "speed of the centre of mass",
    "path_length": "distance travelled by the centre of mass",
    "tip_depth": "depth of the nose tip below the front face, along its normal (negative above it)",
    "attitude": "the unit quaternion that turns the body frame into the world frame (w: its scalar part)",
    "angular_velocity": "the angular velocity, body frame (x along the axis)",
    "axis_angle": "the axis's angle in the vertical plane, from the inward normal towards +x, unwrapped along the run",
    "velocity_angle": "the velocity's angle in the vertical plane, measured as axis_angle",
    "attack_angle": "axis_angle - velocity_angle, signed, wrapped to [-180, 180)",
    "total_attack_angle": "the unsigned 3-D angle between the axis and the velocity",
    "force": "the load on the body, world frame",
    "moment": "the moment about the centre of mass, body frame",
    "resistance_centre_from_tip": "the point R on the axis with M = R x F (least squares over the transverse force),"
    " measured back from the nose tip; empty where the transverse force is below {percent:g} % of the whole force",
}


# ---------------------------------------------------------------- markdown


def cell(text: object) -> str:
    """``text`` as one cell of a markdown table: on one line, its pipes escaped."""
    return " ".join(str(text).split()).replace("|", "\\|")


def table(header: Iterable[str], rows: Iterable[Iterable[object]]) -> list[str]:
    """A markdown table, as lines."""
    names = list(header)
    lines = ["| " + " | ".join(names) + " |", "|" + "---|" * len(names)]
    return lines + ["| " + " | ".join(cell(value) for value in row) + " |" for row in rows]


def plain(text: str | None) -> str:
    """A docstring or description as one line of page text: ``code`` in single backticks, Sphinx roles and
    references to Python modules (``(mesh.measured)``) left out."""
    text = " ".join((text or "").split())
    text = re.sub(r":[a-z]+:`~?(?:[\w.]+\.)?(\w+)`", r"`\1`", text)
    text = re.sub(r"\s*\((?:[a-z_]+\.)+[a-z_]+\)", "", text)
    return text.replace("``", "`")


def first_sentence(text: str | None) -> str:
    """The first sentence of ``text`` (as :func:`plain` gives it), without its full stop."""
    line = plain(text)
    match = re.match(r"(.+?)\.(?:\s|$)", line)
    return match.group(1) if match else line


def number(value: float) -> str:
    """A number as the schema would write it: ``2e-5``, ``1e11``, ``0.5``, ``90``."""
    text = f"{value:.6g}"
    mantissa, _, exponent = text.partition("e")
    return f"{mantissa}e{int(exponent)}" if exponent else text


def toml(value: object) -> str:
    """A default value as a scene file writes it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return number(value)
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml(v)}" for k, v in value.items()) + "}"
    return str(value)


# ---------------------------------------------------------------- types


def unwrap(tp: Any) -> tuple[Any, list[Any]]:
    """The type inside any ``Annotated`` layers, and their metadata (a nested field's constraints included)."""
    metadata: list[Any] = []
    while get_origin(tp) is Annotated:
        tp, *extra = get_args(tp)
        for item in extra:
            metadata.extend(item.metadata if isinstance(item, FieldInfo) else [item])
    return tp, metadata


def alternatives(tp: Any) -> list[Any]:
    """The members of a union, nested unions flattened and ``None`` left out; ``[tp]`` for any other type."""
    tp, _ = unwrap(tp)
    if get_origin(tp) not in (Union, types.UnionType):
        return [tp]
    return [member for arg in get_args(tp) if arg is not type(None) for member in alternatives(arg)]


def is_model(tp: Any) -> TypeGuard[type[BaseModel]]:
    """Whether ``tp`` is a pydantic model: a table of a scene."""
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def describe(tp: Any) -> str:
    """A type in words: ``number``, ``"rk4" or "dopri54"``, ``array of [number, number]``."""
    members = alternatives(tp)
    if len(members) > 1:
        return " or ".join(describe(member) for member in members)
    tp = members[0]
    origin, args = get_origin(tp), get_args(tp)
    if origin is Literal:
        return " or ".join(toml(arg) for arg in args)
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"array of {plural(describe(args[0]))}"
        return "[" + ", ".join(describe(arg) for arg in args) + "]"
    if origin is list:
        return f"array of {plural(describe(args[0]))}"
    if origin is dict:
        return f"table of {plural(describe(args[1]))} by name"
    if is_model(tp):
        return "table"
    return SCALARS.get(tp, getattr(tp, "__name__", str(tp)))


def plural(name: str) -> str:
    return f"{name}s" if name in SCALARS.values() else name


def bounds(metadata: Iterable[Any]) -> list[str]:
    """The numeric bounds and lengths among a field's metadata, in words: ``> 0``, ``<= 1e4``, ``3 to 1000 items``."""
    said, lengths = [], {}
    for item in metadata:
        said += [f"{sign} {number(getattr(item, name))}" for name, sign in BOUNDS.items() if hasattr(item, name)]
        if isinstance(item, annotated_types.MinLen):
            lengths["min_length"] = item.min_length
        if isinstance(item, annotated_types.MaxLen):
            lengths["max_length"] = item.max_length
    if lengths:
        low, high = lengths.get("min_length"), lengths.get("max_length")
        said.append(
            f"{low} to {high} items" if low and high else f"at least {low} items" if low else f"at most {high} items"
        )
    return said


def inner_bounds(tp: Any) -> list[str]:
    """The bounds of the numbers inside an array or table type (a profile's coordinates, a material's density)."""
    found: list[str] = []
    for arg in get_args(unwrap(tp)[0]):
        if arg is Ellipsis or is_model(arg):
            continue
        for said in bounds(unwrap(arg)[1]) + inner_bounds(arg):
            if said not in found:
                found.append(said)
    return found


# ---------------------------------------------------------------- the scene


def unit_of(info: FieldInfo) -> str:
    extra = info.json_schema_extra
    return str(extra.get("unit", "")) if isinstance(extra, dict) else ""


def default_of(info: FieldInfo) -> str:
    if info.is_required():
        return "required"
    value = info.get_default(call_default_factory=True)
    return "not set" if value is None or value is PydanticUndefined else toml(value)


def plausible_range(info: FieldInfo) -> str:
    """The range a physical input plausibly takes (a value outside it is refused as a likely slip of unit), in
    the field's unit and, where it differs, in the unit the message also gives: ``1e5 to 5e8 Pa, about 0.1-500
    MPa``; ``""`` for a field without one."""
    from cases.scene.plausible import plausible_of

    plausible = plausible_of(info)
    if plausible is None:
        return ""
    text = plausible.allowed(plausible.unit or unit_of(info))
    return f"each {plausible.column_name}: {text}" if plausible.column is not None else text


def key_row(key: str, info: FieldInfo, kind: str | None = None) -> list[str]:
    """A table row: key, type, unit, default, allowed range, plausible range, description."""
    annotation = info.annotation
    within = ["each number " + ", ".join(inner)] if (inner := inner_bounds(annotation)) else []
    limits = ", ".join(bounds(info.metadata) + within)
    kind = kind or describe(annotation)
    row = [f"`{key}`", kind, unit_of(info), default_of(info), limits, plausible_range(info)]
    return [*row, plain(info.description)]


def alternative(key: str, model: type[BaseModel]) -> tuple[str, str]:
    """The heading and introduction of one alternative of a union of tables: named by its tag (a key whose only
    value is one string, ``shape = "cone"``), else by the first sentence of its docstring."""
    doc = plain(model.__doc__)
    for name, info in model.model_fields.items():
        values = get_args(info.annotation) if get_origin(info.annotation) is Literal else ()
        if len(values) == 1:
            return f"[{key}] with {name} = {toml(values[0])}", doc
    first = first_sentence(model.__doc__)
    return f"[{key}]: {first}", doc[len(first) + 1 :].strip()


SCENE_HEADER = ("key", "type or allowed values", "unit", "default", "allowed range", "plausible range", "description")


def model_tables(model: type[BaseModel], prefix: str, title: str, level: str, seen: dict[str, str]) -> list[str]:
    """The tables of ``model``'s keys at ``prefix`` (``projectile.nose.``): its own keys, then one table per
    nested table, per alternative of a union of tables, and per element of an array of tables.  ``seen`` maps
    each union already listed (by its type's text) to its key, so that a second use refers to the first."""
    rows, nested = [], []
    for name, info in model.model_fields.items():
        key = f"{prefix}{name}"
        members = alternatives(info.annotation)
        models = [m for m in members if is_model(m)]
        element = get_args(members[0])[0] if get_origin(members[0]) is list else None
        if len(members) == 1 and models:
            intro = plain(models[0].__doc__)
            if not info.is_required() and info.get_default() is None:
                intro += " Optional: absent unless given."
            nested.append((models[0], f"{key}.", f"[{key}]", intro))
        elif models:
            signature = repr(info.annotation)
            if signature in seen:
                rows.append(key_row(key, info, f"as `{seen[signature]}`"))
                continue
            seen[signature] = key
            others = [describe(m) for m in members if not is_model(m)]
            rows.append(key_row(key, info, " or ".join([*others, "one of the tables below"])))
            nested += [(choice, f"{key}.", *alternative(key, choice)) for choice in models]
        elif is_model(element):
            rows.append(key_row(key, info, "array of tables (below)"))
            array = (
                f"An array of tables, `[[{key}]]` in a scene file, one per element"
                f" (`--set {key}=[...]` replaces the whole array)."
            )
            nested.append((element, f"{key}[n].", f"[[{key}]]", f"{plain(element.__doc__)} {array}"))
        else:
            rows.append(key_row(key, info))
    lines = [f"{level} {title}", ""]
    if rows:
        lines += [*table(SCENE_HEADER, rows), ""]
    for sub, sub_prefix, sub_title, intro in nested:
        body = model_tables(sub, sub_prefix, sub_title, "###", seen)
        lines += [*body[:2], *([intro, ""] if intro else []), *body[2:]]
    return lines


def scene_reference() -> str:
    """Every key of a scene file: the scene's own keys, then a section per table of the scene."""
    from cases.scene.schema import Scene

    seen: dict[str, str] = {}
    top = {name: info for name, info in Scene.model_fields.items() if not is_model(info.annotation)}
    lines = [
        "## Top-level keys",
        "",
        plain(Scene.__doc__),
        "",
        *table(SCENE_HEADER, [key_row(k, i) for k, i in top.items()]),
        "",
    ]
    for name, info in Scene.model_fields.items():
        if name in top:
            continue
        model = info.annotation
        assert is_model(model), name
        body = model_tables(model, f"{name}.", f"[{name}]", "##", seen)
        required = "A required table." if info.is_required() else "Optional: every key has a default."
        lines += [*body[:2], f"{plain(model.__doc__)} {required}", "", *body[2:]]
    return "\n".join(lines).rstrip("\n") + "\n"


# ---------------------------------------------------------------- the command line


def shown_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The actions ``parser``'s help lists, in its order: recorded by a help formatter that keeps them instead
    of laying them out (``format_help`` also builds the help texts the code's registries give late)."""
    recorded: list[argparse.Action] = []

    class Recorder(argparse.HelpFormatter):
        def add_arguments(self, actions: Iterable[argparse.Action]) -> None:
            recorded.extend(actions)

    kept = parser.formatter_class
    parser.formatter_class = Recorder
    try:
        parser.format_help()
    finally:
        parser.formatter_class = kept
    return [action for action in recorded if "--help" not in action.option_strings]


def subcommands(parser: argparse.ArgumentParser) -> dict[str, tuple[str, argparse.ArgumentParser]]:
    """Each subcommand of ``parser``: its one-line help and its parser.

    argparse keeps a subcommand's help only where its own formatter reads it: the helps are taken from the
    subcommand list laid out on lines too wide to wrap, a line per subcommand."""
    found: dict[str, tuple[str, argparse.ArgumentParser]] = {}
    for action in shown_actions(parser):
        if not isinstance(action.choices, dict):
            continue
        formatter = argparse.HelpFormatter(parser.prog, width=100_000, max_help_position=10_000)
        formatter.add_argument(action)
        helps = dict(line.strip().partition(" ")[::2] for line in formatter.format_help().splitlines())
        for name, sub in action.choices.items():
            found[name] = (helps.get(name, "").strip(), sub)
    return found


def help_text(action: argparse.Action, prog: str) -> str:
    """An option's help, its ``%(default)s`` filled in as argparse does."""
    text = action.help or ""
    if "%" in text:
        text = text % {**{k: v for k, v in vars(action).items() if v is not argparse.SUPPRESS}, "prog": prog}
    return plain(text)


def value_of(action: argparse.Action) -> str:
    """What an option takes: its choices, its metavar, nothing for a flag."""
    if action.nargs == 0:
        return "(flag)"
    if action.choices is not None:
        return " or ".join(f"`{choice}`" for choice in action.choices)
    metavar = action.metavar if isinstance(action.metavar, str) else action.dest.upper()
    return f"`{metavar}`"


def option_default(action: argparse.Action) -> str:
    if action.required:
        return "required"
    if not action.option_strings:
        return "optional"
    default = action.default
    if action.nargs == 0 or default in (None, [], "", argparse.SUPPRESS):
        return ""
    if isinstance(default, tuple | list):  # a parsed default: written as the metavar says, LOW:HIGH or A,B
        joint = ":" if ":" in str(action.metavar) else ","
        return "`" + joint.join(toml(value) for value in default) + "`"
    return f"`{toml(default) if isinstance(default, float) else default}`"


def option_row(action: argparse.Action, prog: str) -> list[str]:
    """An option's row: its names, value, default and description; a former spelling (hidden from the help,
    ``cases.cli.options.renamed``) says what replaced it."""
    names = ", ".join(f"`{o}`" for o in action.option_strings) or f"`{action.dest}`"
    if action.help == argparse.SUPPRESS:
        return [names, "", "", f"a former spelling, refused in one line: give {plain(str(action.const))}"]
    return [names, value_of(action), option_default(action), help_text(action, prog)]


def option_rows(parser: argparse.ArgumentParser) -> list[list[str]]:
    return [option_row(action, parser.prog) for action in shown_actions(parser) if not isinstance(action.choices, dict)]


def synopsis(parser: argparse.ArgumentParser) -> str:
    """``penetrate run SCENE [options]``: the positional arguments, then the options."""
    words = [parser.prog]
    for action in shown_actions(parser):
        if action.option_strings:
            continue
        metavar = action.metavar if isinstance(action.metavar, str) else action.dest.upper()
        words.append(f"[{metavar}]" if action.nargs == "?" else metavar)
    return " ".join([*words, "[options]"])


CLI_HEADER = ("option", "value", "default", "description")


def cli_reference() -> str:
    """Every command of ``penetrate``: a list of them, the options of ``penetrate`` itself, then each command's
    synopsis and options."""
    from cases.cli import build_parser
    from cases.cli.descriptions import JSON_SHAPES

    parser = build_parser()
    commands = subcommands(parser)
    lines = [
        "## Commands",
        "",
        *table(("command", "what it does"), [[f"`penetrate {n}`", h] for n, (h, _) in commands.items()]),
    ]
    lines += [
        "",
        "Options of `penetrate` itself, given before the command:",
        "",
        *table(CLI_HEADER, option_rows(parser)),
    ]
    for name, (summary, sub) in commands.items():
        lines += ["", f"## penetrate {name}", "", f"{summary[:1].upper()}{summary[1:]}.", "", f"`{synopsis(sub)}`", ""]
        lines += table(CLI_HEADER, option_rows(sub))
        if any("--json" in action.option_strings for action in shown_actions(sub)):
            lines += ["", f"`--json` prints one JSON object: {JSON_SHAPES[name]}."]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- a run's outputs


def history_meaning(column: str) -> str:
    """What a history column holds (its component named for a vector's column)."""
    from cases.run.history import RESISTANCE_CENTRE_FORCE_FRACTION

    base, _, component = column.rpartition("_")
    if column in HISTORY_MEANING:
        text = HISTORY_MEANING[column]
    elif base in HISTORY_MEANING and component in ("w", "x", "y", "z"):
        text = f"{component} component of {HISTORY_MEANING[base]}"
    else:
        raise KeyError(f"history column {column!r} has no meaning in HISTORY_MEANING: add one")
    return text.format(percent=100 * RESISTANCE_CENTRE_FORCE_FRACTION)


def nullable(info: FieldInfo) -> str:
    """`` or null`` for a field that may be None (written as JSON null), else nothing."""
    return " or null" if type(None) in get_args(info.annotation) else ""


def summary_reference() -> str:
    """The fields of a run's summary, then the columns of its ``history.csv``."""
    from cases.run.history import HISTORY_UNITS
    from cases.run.summary import RunSummary

    rows = [
        [f"`{name}`", describe(info.annotation) + nullable(info), unit_of(info), plain(info.description)]
        for name, info in RunSummary.model_fields.items()
    ]
    lines = ["## summary.json and --json", "", first_sentence(RunSummary.__doc__) + ".", ""]
    lines += [*table(("field", "type", "unit", "description"), rows), ""]
    lines += ["## history.csv", "", "One row per recorded step, the columns in this order.", ""]
    lines += table(
        ("column", "unit", "description"), [[f"`{c}`", u, history_meaning(c)] for c, u in HISTORY_UNITS.items()]
    )
    return "\n".join(lines) + "\n"


#: the pages' generators, by the argument that names them
PAGES: dict[str, Callable[[], str]] = {"scene": scene_reference, "cli": cli_reference, "summary": summary_reference}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m docs.reference.generate", description=first_sentence(__doc__))
    parser.add_argument("page", choices=list(PAGES), help="which reference to print")
    sys.stdout.write(PAGES[parser.parse_args(argv).page]())


if __name__ == "__main__":
    main()
