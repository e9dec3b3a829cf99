"""docs/tutorial.md runs as written: its scene file and its commands, in order, in a fresh folder."""

import os
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TUTORIAL = ROOT / "docs" / "tutorial.md"


def blocks() -> list[tuple[str, str]]:
    """The ``bash`` and ``toml`` blocks of the tutorial, as (language, text), in page order."""
    return re.findall(r"```(bash|toml)\n(.*?)```", TUTORIAL.read_text(), flags=re.S)


def test_the_tutorial_scene_is_the_one_its_generated_output_runs():
    files = [text for language, text in blocks() if language == "toml"]
    assert len(files) == 1
    name, _, content = files[0].partition("\n")
    assert name == "# my_projectile.toml"
    assert content == (ROOT / "docs" / "tutorial" / "my_projectile.toml").read_text()


def test_the_tutorial_runs_as_written(tmp_path):
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    (tmp_path / ".venv").symlink_to(ROOT / ".venv")
    commands = 0
    for language, text in blocks():
        if language == "toml":
            name, _, content = text.partition("\n")
            (tmp_path / name.removeprefix("# ")).write_text(content)
            continue
        for line in text.splitlines():
            done = subprocess.run(
                ["bash", "-euo", "pipefail", "-c", line], cwd=tmp_path, capture_output=True, text=True,
                env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=600,
            )  # fmt: skip
            assert done.returncode == 0, f"{line}\n{done.stderr}"
            commands += 1
    assert commands >= 6
    # what the page says the commands write
    for written in ("summary.json", "runs/mine/summary.json", "runs/mine/history.csv", "speeds.csv"):
        assert (tmp_path / written).stat().st_size > 0, written
    for picture in ("field_peak_attack_angle.png", "field_end.png"):
        assert (tmp_path / "renders" / picture).stat().st_size > 0, picture
    assert '"end_reason": "stopped"' in (tmp_path / "summary.json").read_text()
