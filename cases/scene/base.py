"""The building blocks of the scene schema: strict models, numbers that are not booleans, one-line labels."""

from __future__ import annotations

from typing import Annotated, Any, Self

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator
from pydantic.json_schema import JsonDict
from pydantic_core import PydanticCustomError

from .plausible import Plausible, as_extra, check_plausible

__all__ = ["Strict", "Number", "Whole", "Label", "field", "not_boolean"]


def field(
    default: Any = ...,
    *,
    unit: str = "",
    description: str = "",
    plausible: Plausible | None = None,
    **limits: Any,
) -> Any:
    """A model field with its unit recorded for error messages (``json_schema_extra["unit"]``) and, for a physical
    quantity, the range it plausibly takes (``plausible``, one of :mod:`.plausible`'s; checked by every
    :class:`Strict` model after its fields, beyond the hard ``limits``)."""
    extra: JsonDict = {"unit": unit} if unit else {}
    if plausible is not None:
        extra["plausible"] = as_extra(plausible)
    return Field(default, description=description, json_schema_extra=extra or None, **limits)


def not_boolean(value: object) -> object:
    """``true`` is not a number (pydantic would read it as 1)."""
    if isinstance(value, bool):
        raise PydanticCustomError("number_type", "input should be a number, not true or false")
    return value


def _one_line(value: object) -> object:
    """Labels print as one line: no newlines, tabs, escapes or other control characters."""
    if isinstance(value, str) and not value.isprintable():
        raise PydanticCustomError(
            "text_type", "input should be one line of printable text (no newlines, tabs or control characters)"
        )
    return value


Number = Annotated[float, BeforeValidator(not_boolean)]
Whole = Annotated[int, BeforeValidator(not_boolean)]
Label = Annotated[str, BeforeValidator(_one_line)]


class Strict(BaseModel):
    """Forbids unknown keys and non-finite numbers; validates defaults too; fills in the values a formula gives
    (:meth:`_fill_in`) and then refuses a physical input outside its plausible range (:mod:`.plausible`), before
    any check of a subclass that ties fields together."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_default=True)

    @model_validator(mode="after")
    def _plausible_inputs(self) -> Self:
        self._fill_in()
        check_plausible(self)
        return self

    def _fill_in(self) -> None:
        """Fill in the fields a formula gives from the others, each checked against its field's own limits and
        refused naming the input it came from (none here; :class:`~.target.ConcreteLawSpec` fills ``S``)."""
