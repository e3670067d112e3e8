"""Bad input silently accepted or misclassified (issue 18): zero-length traces, a ``colour_by``
naming no field, a joint width that reached OpenCV as a size it cannot parse, and a trace map too
large to analyse in reasonable time.

Oracles: the counts and intensities of a hand-made map (5 features, 2 of them zero-length, in a
10 m x 10 m window: 3 traces, P20 = 3 / 100 m²), the exit code and the message naming the file
and what the test wrote; a monkeypatched statistics function that must not be reached.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockmass.cli import main

from .test_hostile_errors import _fails

WINDOW = {"type": "Feature", "properties": {"role": "window"},
          "geometry": {"type": "Polygon",
                       "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}}


def _map(path: Path, lines: list[tuple[str, list]], window: bool = True) -> Path:
    features = [{"type": "Feature", "properties": {"id": name},
                 "geometry": {"type": "LineString", "coordinates": xy}} for name, xy in lines]
    path.write_text(json.dumps({"type": "FeatureCollection",
                                "features": features + ([WINDOW] if window else [])}))
    return path


SLIPS = [("A", [[1, 1], [8, 2]]), ("B", [[2, 5], [2, 5]]), ("C", [[1, 7], [9, 6]]),
         ("D", [[3, 3], [3, 3], [3, 3]]), ("E", [[5, 1], [5, 9]])]


# ------------------------------------------------------------------------- zero-length traces


def test_zero_length_traces_are_dropped_warned_and_counted(tmp_path, capsys):
    path = _map(tmp_path / "slips.geojson", SLIPS)
    out = tmp_path / "out"
    assert main(["traces", str(path), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"{path}: dropped 2 zero-length traces" in err
    assert "traces [1, 3]" in err and "ids ['B', 'D']" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["Number of Traces"]["value"] == 3
    assert summary["Areal Frequency P20"]["value"] == pytest.approx(3 / 100)
    assert summary["input"]["dropped_zero_length"] == {"count": 2, "trace_indices": [1, 3],
                                                       "ids": ["B", "D"]}
    assert summary["input"]["n_traces"] == 3


def test_the_zero_length_warning_names_the_features_by_their_name_property(tmp_path, capsys):
    path = _map(tmp_path / "slips.geojson", SLIPS)
    doc = json.loads(path.read_text())
    for feature, name in zip(doc["features"], ["A1", "A2", "A3", "A4", "A5"]):
        feature["properties"]["name"] = name
    path.write_text(json.dumps(doc))
    assert main(["traces", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "ids ['B', 'D'], names ['A2', 'A4']" in capsys.readouterr().err


def test_boxcount_drops_zero_length_traces_with_a_warning(tmp_path, capsys):
    path = _map(tmp_path / "slips.geojson", SLIPS)
    assert main(["boxcount", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    assert f"{path}: dropped 2 zero-length traces" in captured.err
    assert json.loads(captured.out)["input"]["n_traces"] == 3


def test_a_map_of_zero_length_traces_only_exits_2_saying_so(tmp_path, capsys):
    path = _map(tmp_path / "dots.geojson", [("B", [[2, 5], [2, 5]])])
    _fails(["traces", str(path)], capsys, 2, f"{path}: the map holds no traces of any length",
           "1 zero-length traces dropped")


def test_traces_outside_the_window_do_not_break_the_map_plot(tmp_path, capsys):
    """The statistics leave out the traces that miss the window; the plot drew every trace with
    the sets of the others (IndexError, exit 1, nothing written)."""
    path = _map(tmp_path / "outside.geojson", [*SLIPS[::2], ("F", [[20, 20], [25, 21]])])
    out = tmp_path / "out"
    assert main(["traces", str(path), "--out", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == {"rose.png", "traces.png", "summary.json",
                                               "manifest.json"}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["diagnostics"]["traces_outside_window"] == 1


# ------------------------------------------------------------------------------ trace budget


def test_a_map_above_the_trace_limit_is_refused_before_its_statistics(tmp_path, capsys,
                                                                     monkeypatch):
    from rockmass import dfn

    def never(*args, **kwargs):
        raise AssertionError("the statistics ran")

    monkeypatch.setattr(dfn, "trace_map_statistics", never)
    path = _map(tmp_path / "big.geojson", SLIPS)
    _fails(["traces", str(path), "--max-traces", "2"], capsys, 2,
           f"{path}: 3 traces, more than the limit of 2 (--max-traces)", "ROCKMASS_MAX_TRACES=N")
    monkeypatch.setenv("ROCKMASS_MAX_TRACES", "2")
    _fails(["traces", str(path)], capsys, 2, "limit of 2 (ROCKMASS_MAX_TRACES)")
    monkeypatch.setenv("ROCKMASS_MAX_TRACES", "lots")
    _fails(["traces", str(path)], capsys, 2, "ROCKMASS_MAX_TRACES must be a positive number")


def test_the_default_trace_limit_refuses_a_million_traces(monkeypatch):
    from rockmass.budgets import DEFAULT_MAX_TRACES, check_traces
    from rockmass.errors import InputError

    monkeypatch.delenv("ROCKMASS_MAX_TRACES", raising=False)
    check_traces(DEFAULT_MAX_TRACES, "map.geojson")
    with pytest.raises(InputError, match=r"map.geojson: 1000000 traces, .* about 3 min"):
        check_traces(10**6, "map.geojson")


def test_raising_the_trace_limit_lets_the_map_through(tmp_path, capsys, monkeypatch):
    path = _map(tmp_path / "map.geojson", SLIPS)
    monkeypatch.setenv("ROCKMASS_MAX_TRACES", "2")
    assert main(["traces", str(path), "--max-traces", "3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["Number of Traces"]["value"] == 3


# ------------------------------------------------------------------------------- colour_by

STUDY = """[blocks]
[blocks.domain]
width_m = 12.0
height_m = 12.0
[blocks.two_sets]
alpha_deg = 30.0
theta_deg = 60.0
spacing_m = [3.0, 4.0]

[study]
colour_by = "{colour_by}"
[study.grid]
blocks.two_sets.theta_deg = [60.0, 90.0]
"""


@pytest.mark.parametrize("colour_by, what", [("blocks.two_sets.thetta_deg", "names no field"),
                                             ("blocks.two_sets", "is a table, not a field")])
def test_colour_by_naming_no_field_exits_2_listing_the_fields(tmp_path, capsys, colour_by, what):
    cfg = tmp_path / "study.toml"
    cfg.write_text(STUDY.format(colour_by=colour_by))
    _fails(["study", str(cfg), "--out", str(tmp_path / "o"), "--list"], capsys, 2,
           f"{cfg}: study.colour_by: '{colour_by}' {what}",
           "blocks.two_sets.theta_deg, blocks.seed")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("colour_by", ["blocks.two_sets.theta_deg", "blocks.two_sets.alpha_deg",
                                       "blocks.seed"])
def test_colour_by_a_varying_or_base_field_is_accepted(tmp_path, capsys, colour_by):
    cfg = tmp_path / "study.toml"
    cfg.write_text(STUDY.format(colour_by=colour_by))
    assert main(["study", str(cfg), "--out", str(tmp_path / "o"), "--list"]) == 0


# ------------------------------------------------------------------ OpenCV errors are bad input


def test_a_joint_width_wider_than_the_photo_exits_2_naming_the_file(tmp_path, capsys):
    """--joint-width 1e9 reached cv2.getStructuringElement as a kernel size it cannot parse: a
    bare TypeError, exit 1."""
    import numpy as np
    from PIL import Image

    grey = np.full((64, 64), 200, np.uint8)
    grey[32, :] = 20
    path = tmp_path / "face.png"
    Image.fromarray(grey).save(path)
    _fails(["extract", str(path), "--m-per-px", "0.01", "--joint-width", "1e9",
            "--out", str(tmp_path / "o")], capsys, 2,
           f"{path}: joint_width_px = 1e+09 px is not narrower than the 64 x 64 pixel image")
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- study: case files up front


def test_study_finds_a_broken_case_trace_file_before_any_case_runs(tmp_path, capsys):
    """A grid over blocks.traces with one good and one broken file: exit 2 naming the config, the
    field, the file and the case, and nothing written (the good case ran first, and the broken one
    failed as its own result)."""
    (tmp_path / "good.csv").write_text("x0,y0,x1,y1\n-5,-4,5,3\n-5,4,4,-5\n", encoding="utf-8")
    (tmp_path / "broken.csv").write_text("x0,y0,x1,y1\n-5,-4,five,3\n", encoding="utf-8")
    cfg = tmp_path / "study.toml"
    cfg.write_text(STUDY.format(colour_by="blocks.two_sets.theta_deg").replace(
        "theta_deg = [60.0, 90.0]", 'theta_deg = [60.0]\n"blocks.traces" = ["good.csv", '
        '"broken.csv"]'))
    _fails(["study", str(cfg), "--out", str(tmp_path / "o"), "--workers", "1"], capsys, 2,
           f"{cfg}: blocks.traces: broken.csv: line 2", "(study case 1: ", "no case has run")
    assert not (tmp_path / "o").exists()


def test_run_refuses_a_trace_map_above_the_limit_before_any_stage(tmp_path, capsys, monkeypatch):
    path = _map(tmp_path / "map.geojson", SLIPS)
    cfg = tmp_path / "run.toml"
    cfg.write_text('[run]\ntraces = "map.geojson"\n')
    monkeypatch.setenv("ROCKMASS_MAX_TRACES", "2")
    _fails(["run", str(cfg), "--out", str(tmp_path / "o")], capsys, 2,
           f"{cfg}: run.traces: map.geojson: 3 traces, more than the limit of 2")
    assert not (tmp_path / "o").exists()
    assert path.exists()
