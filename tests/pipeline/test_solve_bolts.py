"""``[[solve.bolts]]`` through ``rockmass solve``: the TOML section, ``bolts.csv`` and the summary in
``result.json`` (the mechanics are verified in tests/solver/test_bolts.py)."""

from __future__ import annotations

import csv
import json

from rockmass.cli import main

from .test_cli_solve import TINY

# one vertical bolt through the 4 x 2 blocks of TINY, across the joint at y = 0.25 m
BOLT = """
[[solve.bolts]]
name = "b1"
start_xy_m = [0.6, 0.45]
end_xy_m = [0.6, 0.05]
stage = "gravity"
segments = 8
properties = { axial_stiffness_n = 1e8, bond_stiffness_n_m2 = 1e9, bond_strength_n_m = 1e6 }
"""


def test_solve_writes_bolts_csv_from_the_toml_section(tmp_path):
    config = tmp_path / "bolted.toml"
    config.write_text(TINY.format(kn=1e9, ks=1e9) + BOLT)
    assert main(["solve", str(config), "--out", str(tmp_path / "out")]) == 0
    rows = list(csv.DictReader((tmp_path / "out" / "bolts.csv").open()))
    assert len(rows) == 9 and {r["bolt"] for r in rows} == {"b1"}
    assert {"axial_force_n", "yielded", "bond_slip_m", "bond_slipping", "host_block"} <= set(rows[0])
    above = {r["host_block"] for r in rows if float(r["y_m"]) > 0.25}
    below = {r["host_block"] for r in rows if float(r["y_m"]) < 0.25}
    assert len(above) == len(below) == 1 and above != below  # grouted in both blocks
    summary = json.loads((tmp_path / "out" / "result.json").read_text())["bolts"]
    assert [s["bolt"] for s in summary] == ["b1"] and summary[0]["stage"] == "gravity"


def test_solve_without_bolts_writes_no_bolts_csv(tmp_path):
    config = tmp_path / "plain.toml"
    config.write_text(TINY.format(kn=1e9, ks=1e9))
    assert main(["solve", str(config), "--out", str(tmp_path / "out")]) == 0
    assert not (tmp_path / "out" / "bolts.csv").exists()
    assert "bolts" not in json.loads((tmp_path / "out" / "result.json").read_text())
