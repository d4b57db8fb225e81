"""The repository says under which licence it ships and how to cite it, and the two agree with
pyproject.toml and the BARN data's own licence."""

from __future__ import annotations

import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def test_the_license_file_is_the_licence_pyproject_declares() -> None:
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert declared["project"]["license"] == "Apache-2.0"
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.lstrip().startswith("Apache License")
    assert "Version 2.0, January 2004" in text and "END OF TERMS AND CONDITIONS" in text


def test_the_barn_data_keeps_its_mit_licence_and_the_notice_names_it() -> None:
    barn = ROOT / "pic4rl_sim/engine/worlds/data/LICENSE-BARN"
    assert barn.read_text(encoding="utf-8").startswith("MIT License")
    notice = (ROOT / "NOTICE").read_text(encoding="utf-8")
    assert "pic4rl_sim/engine/worlds/data/LICENSE-BARN" in notice and "MIT" in notice


def test_the_citation_credits_the_toolkit_the_paper_and_barn() -> None:
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and cff["license"] == "Apache-2.0"
    version = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert cff["version"] == version["project"]["version"]
    titles = {ref["title"]: ref for ref in cff["references"]}
    paper = titles["PIC4rl-gym: a ROS2 modular framework for Robots Autonomous Navigation "
                   "with Deep Reinforcement Learning"]
    assert [a["family-names"] for a in paper["authors"]] == [
        "Martini", "Eirale", "Cerrato", "Chiaberge"]
    barn = titles["Benchmarking Metric Ground Navigation"]
    assert barn["license"] == "MIT" and barn["year"] == 2020
