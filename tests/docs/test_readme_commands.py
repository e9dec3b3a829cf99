"""The command lines of the README are the commands' real options, and the quick ones run as written."""

import json
import re
import shlex
from pathlib import Path

import pytest

from cases.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]


def commands(page: Path) -> list[str]:
    """Every ``penetrate`` command line of a page's bash blocks (continuations joined, comments, a redirection or a
    pipe cut; a usage synopsis with ``[...]`` left out), without the ``penetrate``."""
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", page.read_text(), flags=re.S):
        for line in re.sub(r"\\\n\s*", " ", block).splitlines():
            line = line.split("  #")[0].split(" # ")[0].strip().removeprefix(".venv/bin/")
            line = re.split(r" [>|] ", line)[0]
            if line.startswith("penetrate ") and " [" not in line:
                lines.append(line.removeprefix("penetrate "))
    return lines


COMMANDS = commands(ROOT / "README.md")


def test_the_readme_shows_commands():
    assert len(COMMANDS) >= 10, COMMANDS
    assert {shlex.split(line)[0] for line in COMMANDS} >= {
        "run",
        "sweep",
        "critical",
        "convergent",
        "paper",
        "compare",
        "ensemble",
    }


@pytest.mark.parametrize("line", COMMANDS)
def test_each_readme_command_parses_and_names_files_that_exist(line):
    args = build_parser().parse_args(shlex.split(line))
    scene = getattr(args, "scene", None)
    if scene is not None:
        assert (ROOT / scene).is_file(), scene


QUICK = [line for line in COMMANDS if line.startswith("run ") and "body.step" not in line]


@pytest.mark.parametrize("line", QUICK)
def test_the_quick_readme_commands_run_as_written(line, tmp_path, monkeypatch, capsys):
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    monkeypatch.chdir(tmp_path)
    assert main(shlex.split(line)) == 0
    printed = capsys.readouterr().out
    if "--json" in line:
        assert json.loads(printed)["end_reason"] in {"stopped", "exited"}
    if "--out" in line:
        out = Path(shlex.split(line)[shlex.split(line).index("--out") + 1])
        assert (out / "summary.json").is_file() and (out / "history.csv").is_file()


def page_commands() -> list[tuple[str, str]]:
    """Every ``penetrate`` command line of the pages of docs/, with its page."""
    return [
        (page.relative_to(ROOT).as_posix(), line)
        for page in sorted((ROOT / "docs").rglob("*.md"))
        for line in commands(page)
    ]


@pytest.mark.parametrize(("page", "line"), page_commands())
def test_each_command_of_the_docs_parses(page, line):
    try:
        build_parser().parse_args(shlex.split(line))
    except SystemExit:
        pytest.fail(f"{page}: penetrate {line}: not a valid command line")
