"""``rockmass traces``: a regular grid with closed-form answers, outputs, and bad input."""

import json

import numpy as np
import pytest

from rockmass.cli import main
from rockmass.dfn import TraceMap, read_traces, trace_map_statistics, write_traces
from rockmass.fractal import box_count


@pytest.fixture
def grid_map(tmp_path):
    """A 10 m x 10 m window: 9 horizontal traces (1 m apart) and 4 vertical ones (2 m apart),
    each crossing the window completely. P21 = (9 + 4) * 10 / 100 = 1.3 m/m²."""
    lines = [np.array([[0.0, y], [10.0, y]]) for y in range(1, 10)]
    lines += [np.array([[x, 0.0], [x, 10.0]]) for x in (2.0, 4.0, 6.0, 8.0)]
    window = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    path = tmp_path / "grid.geojson"
    write_traces(TraceMap.from_polylines(lines, window=window), path)
    return path


def test_regular_grid_has_closed_form_intensity_and_two_sets(grid_map, capsys):
    assert main(["traces", str(grid_map), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["Number of Traces"]["value"] == 13
    assert summary["Fracture Intensity P21"]["value"] == pytest.approx(1.3, rel=1e-12)
    angles = sorted(s["Mean Angle"]["value"] % 180 for s in summary["sets"])
    assert len(angles) == 2
    assert angles[0] == pytest.approx(0.0, abs=0.5) or angles[0] == pytest.approx(180.0, abs=0.5)
    assert angles[1] == pytest.approx(90.0, abs=0.5)
    assert summary["Node Counts"]["X"] == 9 * 4  # every horizontal crosses every vertical


def test_outputs_match_the_api(grid_map, tmp_path):
    out = tmp_path / "out"
    assert main(["traces", str(grid_map), "--out", str(out)]) == 0
    for name in ("summary.json", "rose.png", "traces.png", "manifest.json"):
        assert (out / name).stat().st_size > 0
    written = json.loads((out / "summary.json").read_text())
    trace_map = read_traces(grid_map)
    api = trace_map_statistics(trace_map).to_dict()
    assert written["Fracture Intensity P21"] == api["Fracture Intensity P21"]
    assert written["Box-counting Dimension"]["value"] == box_count(trace_map).dimension


def test_area_file_replaces_the_window(grid_map, tmp_path, capsys):
    area = tmp_path / "area.geojson"
    half = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 10.0], [0.0, 10.0]])
    write_traces(TraceMap.from_polylines([], window=half), area)
    assert main(["traces", str(grid_map), "--area", str(area), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    # inside the left half: 9 horizontal pieces of 5 m and 2 vertical traces of 10 m, over 50 m²
    assert summary["Fracture Intensity P21"]["value"] == pytest.approx((45 + 20) / 50, rel=1e-12)


@pytest.mark.parametrize("content, suffix, fragment", [
    (b"\x89PNG not really", ".png", "suffix"),
    (b'{"type": "FeatureCollection", "features": []}', ".geojson", "no traces"),
])
def test_bad_input_exits_2(tmp_path, capsys, content, suffix, fragment):
    path = tmp_path / f"bad{suffix}"
    path.write_bytes(content)
    out = tmp_path / "out"
    assert main(["traces", str(path), "--out", str(out)]) == 2
    assert fragment in capsys.readouterr().err
    assert not (out / "summary.json").exists()


def test_area_without_polygon_exits_2(grid_map, tmp_path, capsys):
    no_window = tmp_path / "lines.geojson"
    write_traces(TraceMap.from_segments(np.array([[0.0, 0.0, 1.0, 1.0]])), no_window)
    assert main(["traces", str(grid_map), "--area", str(no_window)]) == 2
    assert "polygon" in capsys.readouterr().err
