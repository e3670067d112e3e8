"""``rockmass scanline``: the bundled sample, outputs equal to the API, and bad input (exit 2)."""

import json
from pathlib import Path

import pytest

from rockmass.cli import main
from rockmass.dfn.scanline import read_scanline
from rockmass.dfn.scanline_stats import scanline_statistics
from rockmass.dfn.sets3d import fit_sets_3d

SAMPLE = Path(__file__).resolve().parents[2] / "samples" / "scanline_seed001.csv"


def test_sample_gives_the_three_seed001_sets_and_writes_every_output(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["scanline", str(SAMPLE), "--out", str(out)]) == 0
    assert "3 set(s) by bic" in capsys.readouterr().out
    for name in ("summary.json", "stereonet.png", "manifest.json"):
        assert (out / name).stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    means = sorted((round(s["mean_dip_direction_deg"] / 10) * 10 % 360, s["mean_dip_deg"]) for s in summary["sets"])
    # Kiran & Juneja 2022, Table 1: 80/10, 70/150, 50/270 (dip directions to the nearest 10°, dips within 10°)
    assert [m[0] for m in means] == [10, 150, 270]
    assert [d for _, d in means] == pytest.approx([80, 70, 50], abs=10)
    # the same numbers as the API
    scanline = read_scanline(SAMPLE)
    sets = fit_sets_3d(scanline.poles())
    api = scanline_statistics(scanline, sets.membership, sets.fits)
    assert summary["sets"][0]["p10_terzaghi_per_m"] == api["sets"][0]["p10_terzaghi_per_m"]
    assert summary["all"] == api["all"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["inputs"][0]["path"] == str(SAMPLE)


def test_json_flag_prints_the_summary_and_sets_flag_is_obeyed(capsys):
    assert main(["scanline", str(SAMPLE), "--json", "--sets", "2", "--terzaghi-cap", "20"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["set_selection"]["n_sets"] == 2 and summary["set_selection"]["selected_by"] == "given"
    assert summary["scanline"]["terzaghi_cap_deg"] == 20.0


@pytest.mark.parametrize("text, args, fragment", [
    ("# trend: 0\n# plunge: 0\n# length: 5\ndistance,dip,dip_direction\n1,nan,3\n", [],
     "line 5, column 'dip'"),
    ("# trend: 0\n# plunge: 0\n# length: 5\ndistance,dip,dip_direction\n6,30,3\n", [], "column 'distance'"),
    ("distance,dip,dip_direction\n1,30,3\n", [], "trend is missing"),
    ("", [], "empty scanline file"),
    ("# trend: 0\n# plunge: 0\n# length: 5\ndistance,dip,dip_direction\n1,30,3\n", ["--terzaghi-cap", "0"],
     "--terzaghi-cap"),
    ("# trend: 0\n# plunge: 0\n# length: 5\ndistance,dip,dip_direction\n1,30,3\n", ["--sets", "2"], "--sets"),
])
def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys, text, args, fragment):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["scanline", str(path), "--out", str(out), *args]) == 2
    assert fragment in capsys.readouterr().err
    assert not out.exists()


def test_missing_file_exits_2(tmp_path, capsys):
    assert main(["scanline", str(tmp_path / "nothing.csv")]) == 2
    assert "nothing.csv" in capsys.readouterr().err


def test_bundled_sample_is_what_its_script_makes():
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_scanline_sample", SAMPLE.with_name("make_scanline_sample.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = [line.split(",") for line in SAMPLE.read_text().splitlines() if line and not line.startswith("#")][1:]
    expected = [[f"{d:.2f}", str(a), str(b), f"{t:.1f}", str(e)] for d, a, b, t, e in module.make_rows()]
    assert rows == expected
