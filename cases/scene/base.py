"""The building blocks of the scene schema: strict models, numbers that are not booleans, one-line labels."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field
from pydantic.json_schema import JsonDict
from pydantic_core import PydanticCustomError

__all__ = ["Strict", "Number", "Whole", "Label", "field", "not_boolean"]


def field(default: Any = ..., *, unit: str = "", description: str = "", **limits: Any) -> Any:
    """A model field with its unit recorded for error messages (``json_schema_extra["unit"]``)."""
    extra: JsonDict | None = {"unit": unit} if unit else None
    return Field(default, description=description, json_schema_extra=extra, **limits)


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
    """Forbids unknown keys and non-finite numbers; validates defaults too."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_default=True)
