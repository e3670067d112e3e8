"""``rockmass boxcount``: outputs, JSON on stdout, exit codes, and nothing partial on bad input."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rockmass.cli import main
from rockmass.fractal import box_count

REPO = Path(__file__).resolve().parents[2]
SAMPLE = REPO / "samples" / "face_traces.geojson"


def _geojson(path: Path, lines, window=None) -> Path:
    features = [{"type": "Feature", "properties": {"id": i},
                 "geometry": {"type": "LineString", "coordinates": line}}
                for i, line in enumerate(lines)]
    if window is not None:
        features.append({"type": "Feature", "properties": {"role": "window"},
                         "geometry": {"type": "Polygon", "coordinates": [window]}})
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    return path


def _png(path: Path, image: np.ndarray) -> Path:
    import cv2

    assert cv2.imwrite(str(path), image)
    return path


def test_sample_box_count_is_the_same_from_cli_and_api(tmp_path, capsys):
    from rockmass.dfn import read_traces

    out = tmp_path / "out"
    assert main(["boxcount", str(SAMPLE), "--out", str(out), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads((out / "boxcount.json").read_text())
    api = box_count(read_traces(SAMPLE))
    assert printed == written
    assert written["dimension"] == api.dimension
    assert written["counts"] == api.counts.tolist()
    assert written["offsets"]["dimensions"] == api.offset_dimensions.tolist()
    assert (out / "boxcount.png").stat().st_size > 10_000
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["inputs"][0]["sha256"]
    assert manifest["config"]["fractal"]["grid"] == 360


def test_flags_override_config_file(tmp_path, capsys):
    trace_file = _geojson(tmp_path / "t.geojson", [[[0, 0], [3, 1]], [[0, 2], [3, 0]]])
    config = tmp_path / "c.toml"
    config.write_text('[fractal]\ngrid = 720\nmethod = "vector"\n')
    assert main(["boxcount", str(trace_file), "--config", str(config), "--grid", "180",
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["grid"] == 180 and doc["method"] == "vector"


def test_binary_image_input(tmp_path, capsys):
    img = np.zeros((360, 360), np.uint8)
    img[100, :] = 255
    assert main(["boxcount", str(_png(tmp_path / "line.png", img)), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["dimension"] == pytest.approx(1.0, abs=1e-12)
    assert doc["input"]["kind"] == "image"


def _fails_with_2(args, capsys, *fragments):
    code = main(args)
    err = capsys.readouterr().err
    assert code == 2, err
    for fragment in fragments:
        assert fragment in err, err
    return err


def test_missing_file_exits_2(tmp_path, capsys):
    _fails_with_2(["boxcount", str(tmp_path / "nope.geojson")], capsys, "nope.geojson")


def test_nan_coordinate_names_the_feature_and_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "bad.geojson"
    bad.write_text('{"type": "FeatureCollection", "features": ['
                   '{"type": "Feature", "properties": {"id": "A"}, "geometry": {"type": '
                   '"LineString", "coordinates": [[0, 0], [1, 1]]}},'
                   '{"type": "Feature", "properties": {"id": "B"}, "geometry": {"type": '
                   '"LineString", "coordinates": [[0, 0], [NaN, 1]]}}]}')
    out = tmp_path / "out"
    _fails_with_2(["boxcount", str(bad), "--out", str(out)], capsys, "bad.geojson", "id=B")
    assert not out.exists()


def test_empty_image_exits_2_naming_the_file(tmp_path, capsys):
    path = _png(tmp_path / "empty.png", np.zeros((50, 50), np.uint8))
    _fails_with_2(["boxcount", str(path)], capsys, "empty.png", "empty")


def test_empty_trace_map_exits_2_naming_the_file(tmp_path, capsys):
    path = tmp_path / "none.geojson"
    path.write_text('{"type": "FeatureCollection", "features": []}')
    _fails_with_2(["boxcount", str(path)], capsys, "none.geojson", "no traces")


def test_unwritable_output_exits_1_naming_the_path(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    code = main(["boxcount", str(SAMPLE), "--out", str(blocker / "out")])
    err = capsys.readouterr().err
    assert code == 1, err
    assert "a_file" in err and "cannot write" in err


def test_range_on_a_large_image_is_checked_against_its_own_grid(tmp_path, capsys):
    img = np.zeros((1000, 1000), np.uint8)
    img[500, :] = 255
    path = _png(tmp_path / "big.png", img)
    assert main(["boxcount", str(path), "--range", "1", "250", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["grid"] == 1000 and doc["settings"]["grid"] == 1000
    assert doc["fit_range_px"] == [1.0, 250.0]


def test_flag_errors_name_the_flag(tmp_path, capsys):
    _fails_with_2(["boxcount", str(SAMPLE), "--offsets", "0"], capsys, "--offsets")


def test_no_invert_overrides_the_config(tmp_path, capsys):
    img = np.zeros((60, 60), np.uint8)
    img[30, :] = 255
    path = _png(tmp_path / "line.png", img)
    config = tmp_path / "c.toml"
    config.write_text("[fractal]\ninvert = true\nthreshold = 100.0\n")
    assert main(["boxcount", str(path), "--config", str(config), "--no-invert", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["dimension"] == pytest.approx(1.0, abs=1e-12)


def test_lines_drawn_by_opacity_on_a_transparent_canvas(tmp_path, capsys):
    rgba = np.zeros((60, 60, 4), np.uint8)
    rgba[30, :, 3] = 255  # black lines whose only signal is the alpha channel
    path = _png(tmp_path / "alpha.png", rgba)
    assert main(["boxcount", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["dimension"] == pytest.approx(1.0, abs=1e-12)


def test_unreadable_image_exits_2(tmp_path, capsys):
    path = tmp_path / "garbage.png"
    path.write_bytes(b"this is not a png")
    _fails_with_2(["boxcount", str(path)], capsys, "garbage.png")


def test_grey_image_without_threshold_exits_2(tmp_path, capsys):
    path = _png(tmp_path / "grey.png", np.arange(2500, dtype=np.uint16).reshape(50, 50).astype(np.uint8))
    _fails_with_2(["boxcount", str(path)], capsys, "threshold")


def test_grid_too_small_for_range_exits_2(tmp_path, capsys):
    trace_file = _geojson(tmp_path / "t.geojson", [[[0, 0], [3, 1]]])
    _fails_with_2(["boxcount", str(trace_file), "--grid", "16", "--range", "5", "16"], capsys,
                  "box sizes")


def test_bad_config_names_file_and_field(tmp_path, capsys):
    trace_file = _geojson(tmp_path / "t.geojson", [[[0, 0], [3, 1]]])
    config = tmp_path / "c.toml"
    config.write_text("[fractal]\ngridd = 360\n")
    _fails_with_2(["boxcount", str(trace_file), "--config", str(config)], capsys, "c.toml",
                  "fractal.gridd")


def test_unknown_suffix_exits_2(tmp_path, capsys):
    path = tmp_path / "traces.xyz"
    path.write_text("1 2 3")
    _fails_with_2(["boxcount", str(path)], capsys, ".geojson", ".png")


def test_console_script_exit_codes():
    ok = subprocess.run([sys.executable, "-m", "rockmass", "boxcount", str(SAMPLE)],
                        capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    assert ok.stdout.startswith("D = ")
    bad = subprocess.run([sys.executable, "-m", "rockmass", "boxcount", "missing.csv"],
                         capture_output=True, text=True)
    assert "missing.csv" in bad.stderr
    assert bad.returncode == 2 and "missing.csv" in bad.stderr
    usage = subprocess.run([sys.executable, "-m", "rockmass", "boxcount"], capture_output=True,
                           text=True)
    assert usage.returncode == 2


def test_image_too_large_for_its_own_grid_names_the_image_not_grid(tmp_path, capsys):
    """An image wider than the largest grid failed with "--grid must be <= 16384, got ..." though
    no --grid was given; now the message names the file and its size (exit 2)."""
    image = np.zeros((8, 16385), np.uint8)
    image[4, :] = 255
    path = _png(tmp_path / "wide.png", image)
    err = _fails_with_2(["boxcount", str(path)], capsys, "wide.png", "16385 x 8 pixels")
    assert "--grid" not in err
