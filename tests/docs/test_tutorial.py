"""docs/tutorial.md runs as written: its scene files and its commands, in order, in a fresh folder."""

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIAL = ROOT / "docs" / "tutorial.md"
#: a ``toml`` block that changes one table of a scene file written before: ``# NAME: BASE with this [TABLE] table``
EDIT = re.compile(r"# (?P<name>\S+): (?P<base>\S+) with this \[(?P<table>\w+)\] table")


def blocks() -> list[tuple[str, str]]:
    """The ``bash`` and ``toml`` blocks of the tutorial, as (language, text), in page order."""
    return re.findall(r"```(bash|toml)\n(.*?)```", TUTORIAL.read_text(), flags=re.S)


def scene_file(text: str, written: dict[str, str]) -> tuple[str, str]:
    """A ``toml`` block as the file a reader writes, ``(name, content)``: a block headed ``# NAME`` is the whole
    file; one headed as :data:`EDIT` is a file already ``written`` with that table replaced by the block."""
    header, _, content = text.partition("\n")
    if edit := EDIT.fullmatch(header):
        table = re.compile(rf"^\[{edit['table']}\]\n.*?(?=^\[|\Z)", flags=re.M | re.S)
        base = written[edit["base"]]
        assert table.search(base), f"{edit['base']} has no [{edit['table']}] table"
        return edit["name"], table.sub(lambda _: content + "\n", base, count=1)
    assert header.startswith("# ") and header.endswith(".toml"), header
    return header.removeprefix("# "), content


def scene_files() -> dict[str, str]:
    """Every scene file the tutorial has the reader write, by name, in page order."""
    written: dict[str, str] = {}
    for language, text in blocks():
        if language == "toml":
            name, content = scene_file(text, written)
            written[name] = content
    return written


def test_the_tutorial_scenes_are_the_ones_its_generated_outputs_run():
    written = scene_files()
    assert list(written) == ["my_projectile.toml", "my_shell.toml", "my_slab.toml"]
    for name, content in written.items():
        assert content == (ROOT / "docs" / "tutorial" / name).read_text(), name


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_the_tutorial_runs_as_written(tmp_path):
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    (tmp_path / ".venv").symlink_to(ROOT / ".venv")
    commands, written = 0, {}
    for language, text in blocks():
        if language == "toml":
            name, content = scene_file(text, written)
            written[name] = content
            (tmp_path / name).write_text(content)
            continue
        for line in text.splitlines():
            done = subprocess.run(
                ["bash", "-euo", "pipefail", "-c", line], cwd=tmp_path, capture_output=True, text=True,
                env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=600,
            )  # fmt: skip
            assert done.returncode == 0, f"{line}\n{done.stderr}"
            commands += 1
    assert commands >= 11
    # what the page says the commands write
    for written_file in ("summary.json", "runs/mine/summary.json", "runs/mine/history.csv", "runs/speeds/sweep.csv"):
        assert (tmp_path / written_file).stat().st_size > 0, written_file
    for picture in ("field_peak_attack_angle.png", "field_end.png"):
        assert (tmp_path / "renders" / picture).stat().st_size > 0, picture
    assert '"end_reason": "stopped"' in (tmp_path / "summary.json").read_text()
