"""Issue 19, measured defects as tests: silent areas, lon/lat files, angle conventions, the small
command-line defects (``dfn --json``, ``--out`` on a file, set orientations in the report,
``Stage(excavate=("tunnel",))``).

The maps are small and generated: traces whose P21 over a given area is worked out by hand.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from rockmass.cli import main
from rockmass.dfn import TraceMap, write_traces

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

#: 6 parallel traces of 4 m in a mapped area of 10 m x 10 m: P21 = 24 / 100 = 0.24 m/m²; their
#: bounding box is 4 m x 5 m (P21 1.2) — the area a silent default took (issue 19: 0.659 for 1.263)
LINES = [np.array([[3.0, 2.0 + k], [7.0, 2.0 + k]]) for k in range(6)]
AREA = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]


@pytest.fixture
def no_window(tmp_path):
    path = tmp_path / "map.geojson"
    write_traces(TraceMap.from_polylines(LINES, frame="map", crs="EPSG:32633"), path)
    return path


@pytest.fixture
def area_file(tmp_path):
    path = tmp_path / "area.geojson"
    write_traces(TraceMap.from_polylines([], window=AREA, frame="map", crs="EPSG:32633"), path)
    return path


# -- 1. areas are never silent -------------------------------------------------------------------


def test_map_without_area_exits_2_naming_the_file_and_what_to_pass(no_window, capsys):
    assert main(["traces", str(no_window)]) == 2
    err = capsys.readouterr().err
    assert "map.geojson" in err and "no sampling area" in err
    assert "--area AREA.geojson" in err and "--area bbox" in err and "--area hull" in err


def test_area_file_gives_the_intensity_of_the_mapped_area(no_window, area_file, capsys):
    assert main(["traces", str(no_window), "--area", str(area_file), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["Fracture Intensity P21"]["value"] == pytest.approx(0.24, rel=1e-12)
    assert summary["input"]["area"]["choice"] == "file" and summary["window"]["source"] == "argument"


@pytest.mark.parametrize("choice, area, source", [("bbox", 20.0, "bounding_box"), ("hull", 20.0, "convex_hull")])
def test_bbox_and_hull_are_explicit_and_named_in_every_output(no_window, tmp_path, capsys, choice, area, source):
    out = tmp_path / "out"
    assert main(["traces", str(no_window), "--area", choice, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"--area {choice}" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["Area"]["value"] == pytest.approx(area)
    assert summary["window"]["source"] == source and summary["input"]["area"]["choice"] == choice
    assert json.loads((out / "manifest.json").read_text())["config"]["area"] == choice


def test_window_in_the_file_keeps_the_old_behaviour(tmp_path, capsys):
    path = tmp_path / "with_window.geojson"
    write_traces(TraceMap.from_polylines(LINES, window=AREA), path)
    assert main(["traces", str(path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["Fracture Intensity P21"]["value"] == pytest.approx(0.24, rel=1e-12)
    assert summary["input"]["area"]["choice"] == "map_window"


def test_area_in_another_crs_exits_2(no_window, tmp_path, capsys):
    other = tmp_path / "other.geojson"
    write_traces(TraceMap.from_polylines([], window=AREA, frame="map", crs="EPSG:3067"), other)
    assert main(["traces", str(no_window), "--area", str(other)]) == 2
    assert "EPSG:3067" in capsys.readouterr().err


def _run_config(folder, traces, area=None):
    lines = ["[run]", f"traces = {json.dumps(str(traces))}", 'stages = ["traces"]']
    if area is not None:
        lines.append(f"area = {json.dumps(str(area))}")
    path = folder / "run.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_run_without_area_exits_2_naming_run_area(no_window, tmp_path, capsys):
    assert main(["run", str(_run_config(tmp_path, no_window)), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "run.area" in err and 'area = "bbox"' in err and "map.geojson" in err
    assert not (tmp_path / "out" / "traces").exists()


def test_run_accepts_the_area_and_its_report_names_it(no_window, area_file, tmp_path):
    out = tmp_path / "out"
    assert main(["run", str(_run_config(tmp_path, no_window, area_file)), "--out", str(out)]) == 0
    summary = json.loads((out / "traces" / "summary.json").read_text())
    assert summary["Fracture Intensity P21"]["value"] == pytest.approx(0.24, rel=1e-12)
    assert "the polygon of" in (out / "report.html").read_text()
    hashed = json.loads((out / "traces" / "stage.json").read_text())
    assert hashed["sections"]["run.area"] == str(area_file)
    assert str(area_file) in hashed["inputs"]


def test_run_area_hull_is_named_in_the_summary(no_window, tmp_path):
    out = tmp_path / "out"
    assert main(["run", str(_run_config(tmp_path, no_window, "hull")), "--out", str(out)]) == 0
    summary = json.loads((out / "traces" / "summary.json").read_text())
    assert summary["input"]["area"]["choice"] == "hull" and summary["window"]["source"] == "convex_hull"


def test_study_config_accepts_the_run_area(tmp_path):
    from rockmass.study_config import load_study

    path = tmp_path / "study.toml"
    path.write_text('[run]\narea = "bbox"\n\n' + (SAMPLES / "study_cavern.toml").read_text())
    document, _ = load_study(path)
    assert document.run.area == "bbox"


# -- 2. coordinate systems -----------------------------------------------------------------------


def test_lonlat_file_exits_2_saying_to_reproject(tmp_path, capsys):
    path = tmp_path / "lonlat.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection",
                                "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},
                                "features": [{"type": "Feature", "properties": {}, "geometry": {
                                    "type": "LineString", "coordinates": [[24.94, 60.17], [24.941, 60.1705]]}}]}))
    assert main(["traces", str(path), "--area", "bbox"]) == 2
    err = capsys.readouterr().err
    assert "lonlat.geojson" in err and "geographic" in err and "projected CRS" in err


def test_summary_carries_the_crs_and_the_frame(no_window, capsys):
    assert main(["traces", str(no_window), "--area", "bbox", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["crs"], summary["frame"]) == ("EPSG:32633", "map")
    assert (summary["input"]["crs"], summary["input"]["frame"]) == ("EPSG:32633", "map")


# -- 3. azimuths ---------------------------------------------------------------------------------


def test_map_angles_are_azimuths_in_summary_and_text(no_window, capsys):
    # East-West traces: azimuth 090 on a map (counter-clockwise from East they were 0°)
    assert main(["traces", str(no_window), "--area", "bbox", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["angle_convention"] == "azimuth"
    assert summary["sets"][0]["Mean Angle"]["value"] == pytest.approx(90.0, abs=1e-9)
    assert summary["traces"]["angle_deg"] == pytest.approx([90.0] * 6, abs=1e-9)
    assert main(["traces", str(no_window), "--area", "bbox"]) == 0
    text = capsys.readouterr().out
    assert "azimuth 090.0°" in text and "clockwise from North" in text


def test_face_angles_keep_the_face_convention_and_say_so(tmp_path, capsys):
    path = tmp_path / "face.geojson"
    write_traces(TraceMap.from_polylines(LINES, window=AREA), path)
    assert main(["traces", str(path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["angle_convention"] == "face" and summary["frame"] == "face" and summary["crs"] is None
    assert summary["sets"][0]["Mean Angle"]["value"] == pytest.approx(0.0, abs=1e-9)


# -- 7. small defects ----------------------------------------------------------------------------


def test_dfn_prints_json_like_the_other_subcommands(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["dfn", str(SAMPLES / "dfn_seed001.toml"), "--out", str(out), "--realizations", "1",
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["fitted"] is None and [r["index"] for r in doc["realizations"]] == [0]
    on_disk = json.loads((out / "realization_0000" / "summary.json").read_text())
    assert doc["realizations"][0]["summary"] == on_disk


@pytest.mark.parametrize("command", [
    ["traces", str(SAMPLES / "face_traces.geojson")],
    ["dfn", str(SAMPLES / "dfn_seed001.toml"), "--realizations", "1"],
    ["scanline", str(SAMPLES / "quickstart_scanline.csv")],
])
def test_out_naming_an_existing_file_exits_2_before_any_work(tmp_path, capsys, command):
    blocker = tmp_path / "a_file"
    blocker.write_text("my notes")
    assert main([*command, "--out", str(blocker)]) == 2
    err = capsys.readouterr().err
    assert "a_file" in err and "existing file, not a folder" in err
    assert blocker.read_text() == "my notes"


def test_report_prints_set_orientations_as_the_command_line_does(capsys):
    from rockmass.run_report import _orientation_text
    from rockmass.scanline_cmd import summary_text

    orientation = {"distribution": "fisher", "dip_deg": 68.97106318146524,
                   "dip_direction_deg": 29.017025607347534, "kappa": 21.88}
    assert _orientation_text(orientation) == "fisher 69/029, κ 21.9"  # was "fisher 69/29"
    assert main(["scanline", str(SAMPLES / "quickstart_scanline.csv")]) == 0
    assert "set 0: 69/029" in capsys.readouterr().out


def test_dfn_fit_gives_the_scanline_stages_sets_whatever_the_realization_seed(tmp_path, capsys):
    # With 3 sets the clustering of this scanline has two local optima: seeded with dfn.seed (3)
    # the fit found 63/028 where `rockmass scanline` (seed 0) found 72/029 (the report's 69/29
    # against the command line's 63/027 of issue 19)
    config = tmp_path / "fit.toml"
    config.write_text(f"""[dfn]
seed = 3
realizations = 1
max_fractures = 20000
[dfn.domain]
min_m = [0.0, 0.0, 0.0]
max_m = [6.0, 6.0, 6.0]
[dfn.fit]
scanlines = [{json.dumps(str(SAMPLES / "quickstart_scanline.csv"))}]
n_sets = 3
size = {{ distribution = "power_law", r_min_m = 1.0, r_max_m = 5.0, alpha = 2.5 }}
""")
    assert main(["scanline", str(SAMPLES / "quickstart_scanline.csv"), "--sets", "3", "--json"]) == 0
    scanline = json.loads(capsys.readouterr().out)
    expected = sorted((round(s["mean_dip_deg"], 6), round(s["mean_dip_direction_deg"], 6))
                      for s in scanline["sets"])
    for seed in ("3", "7"):
        assert main(["dfn", str(config), "--out", str(tmp_path / f"out{seed}"), "--seed", seed]) == 0
        fitted = json.loads((tmp_path / f"out{seed}" / "fitted.json").read_text())
        got = sorted((round(s["orientation"]["dip_deg"], 6), round(s["orientation"]["dip_direction_deg"], 6))
                     for s in fitted["sets"])
        assert got == expected


def test_stage_excavating_by_name_says_it_takes_region_numbers():
    from rockmass.solver import Stage

    with pytest.raises(ValueError, match=r"excavate.*region numbers.*'tunnel'.*region_names\.index"):
        Stage("tunnel", excavate=("tunnel",))
    assert Stage("tunnel", excavate=(1,)).excavate == (1,)
