"""Bad input: the one error type every command turns into one line and exit code 2."""

from __future__ import annotations

__all__ = ["InputError", "SceneError", "one_line"]


def one_line(text: object) -> str:
    """``text`` with every control character (newline, escape, ...) shown as an escape, so it prints as one line."""
    return "".join(ch if ch.isprintable() or ch == " " else ascii(ch)[1:-1] for ch in str(text))


class InputError(ValueError):
    """Input that cannot be used (a scene, an option, a file); the message is one line meant for the user.

    It names what is wrong (a scene field by its dotted path, an option by its flag) and what is allowed.
    """

    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))


class SceneError(InputError):
    """A scene that cannot be used: unreadable, not TOML, or a field outside its allowed range."""
