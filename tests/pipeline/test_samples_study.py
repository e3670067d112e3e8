"""Every ``samples/study_*.toml`` validates: ``rockmass study X --out tmp --list`` exits 0 and lists
the expected number of cases (each case is validated as a whole config; nothing runs)."""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import pytest

from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
STUDIES = sorted(SAMPLES.glob("study_*.toml"))

# cases per sample (a new sample adds its line here)
EXPECTED = {
    "study_bolting_seed000.toml": 3,  # no bolts, pattern 1, pattern 2 (seed 000 Fig. 5)
    "study_bolting_seed000_deformable.toml": 3,  # the same with deformable blocks
    "study_cavern.toml": 18,         # theta 40/60/90 x 3 spacings x 2 realizations
    "study_cavern_deformable.toml": 18,  # the same with deformable blocks
    "study_dfn_seed001.toml": 6,     # P32 = 1, 2 x 3 realizations
    "study_seed000.toml": 81,        # theta x alpha x spacings (3 each) x 3 realizations
    "study_shaketable.toml": 13,     # one parameter at a time (seed 002 §4) x 1 realization
}


def _flatten(table: dict) -> dict:
    out = {}
    for k, v in table.items():
        if isinstance(v, dict):
            out.update({f"{k}.{kk}": vv for kk, vv in _flatten(v).items()})
        else:
            out[k] = v
    return out


def test_there_are_study_samples():
    assert {p.name for p in STUDIES} >= {"study_cavern.toml", "study_dfn_seed001.toml"}


@pytest.mark.parametrize("sample", STUDIES, ids=[p.name for p in STUDIES])
def test_study_sample_validates_and_lists_its_cases(sample, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["study", str(sample), "--out", str(out), "--list"]) == 0, capsys.readouterr().err
    lines = capsys.readouterr().out.strip().splitlines()
    study = tomllib.loads(sample.read_text(encoding="utf-8"))["study"]
    grid = _flatten(study.get("grid", {}))
    n = study.get("realizations", 1) * max(len(study.get("cases", [])), 1) \
        * math.prod(len(v) for v in grid.values())
    assert sample.name in EXPECTED, f"add {sample.name} to EXPECTED"
    assert len(lines) == n == EXPECTED[sample.name]
    assert all(re.match(r"\s*\d+\s+[0-9a-f]{16}\s+pending\s+r=\d+ seed=\d+", line) for line in lines)
    assert not out.exists()  # --list writes nothing
    # the header says how to run it
    assert f"rockmass study samples/{sample.name}" in sample.read_text(encoding="utf-8")
