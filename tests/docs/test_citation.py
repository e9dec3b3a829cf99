"""LICENSE and CITATION.cff exist and agree with pyproject.toml."""

import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def test_the_citation_file_is_valid_and_agrees_with_the_project():
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert citation["cff-version"] == "1.2.0"
    assert {"message", "title", "authors", "version", "license"} <= set(citation)
    assert citation["version"] == project["version"]
    assert citation["license"] == project["license"]
    for reference in citation["references"]:
        assert reference["title"] and reference["authors"] and reference["year"]


def test_the_license_is_the_one_pyproject_names():
    assert project_license() == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")


def project_license() -> str:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"]
