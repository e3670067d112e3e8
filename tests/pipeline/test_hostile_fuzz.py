"""Table-driven bad inputs (issue 18, "done when"): every one exits 2 with a message naming the
file, prints no traceback, and leaves no output folder behind (nothing half-written).

Each table row is a file a careful user could hand over by mistake: empty, truncated, the wrong
format behind the right suffix, non-UTF-8, NUL bytes, numbers that are not finite or too large,
structures nested too deep, fields over the csv module's limit. The oracle is the contract of
docs/design.md §4 (exit 2, the file named) and an absent --out.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
SCANLINE = (SAMPLES / "quickstart_scanline.csv").read_text()


def _fc(*coordinates) -> str:
    return json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "LineString", "coordinates": c}}
        for c in coordinates]})


TRACE_FILES = {
    "empty.geojson": b"",
    "truncated.geojson": _fc([[0, 0], [1, 1]])[:40].encode(),
    "array.geojson": b"[]",
    "features-not-list.geojson": b'{"type": "FeatureCollection", "features": 3}',
    "null-geometry.geojson": b'{"type": "FeatureCollection", "features": [{"type": "Feature", '
                             b'"properties": {}, "geometry": null}]}',
    "nan.geojson": _fc([[0, 0], [float("nan"), 1]]).encode(),
    "strings.geojson": _fc([["a", "b"], [1, 1]]).encode(),
    "overflow.geojson": _fc([[0, 0], [1e308, 1e308]], [[0, 1], [1, 0]]).encode(),
    "deep.geojson": b"[" * 50_000 + b"]" * 50_000,
    "binary.geojson": bytes(range(256)) * 4,
    "latin1.geojson": _fc([[0, 0], [1, 1]]).replace("{}", '{"name": "caf\\u00e9"}')
                      .encode().replace(b"caf\\u00e9", b"caf\xe9"),
    "point.geojson": b'{"type": "FeatureCollection", "features": [{"type": "Feature", '
                     b'"properties": {}, "geometry": {"type": "Point", "coordinates": [0, 0]}}]}',
    "empty.csv": b"",
    "header-only.csv": b"trace_id,x,y\n",
    "wrong-columns.csv": b"a,b,c\n1,2,3\n",
    "text-x.csv": b"trace_id,x,y\n1,zero,0\n1,1,1\n",
    "ragged.csv": b"trace_id,x,y\n1,0,0\n1,1\n",
    "huge-field.csv": b"trace_id,x,y\n1,\"" + b"1" * 200_000 + b"\",0\n1,1,1\n",
    "nul.csv": b"trace_id,x,y\n1,0\x00,0\n1,1,1\n",
    "two-frames.csv": b"# frame: face\n# frame: plan\ntrace_id,x,y\n1,0,0\n1,1,1\n",
    "inf.csv": b"trace_id,x,y\n1,0,0\n1,inf,1\n",
    "notes.txt": b"not a trace map",
}

SCANLINE_FILES = {
    "empty.csv": "",
    "header-only.csv": "\n".join(SCANLINE.splitlines()[:7]) + "\n",
    "no-length.csv": SCANLINE.replace("# length: 30.000000\n", ""),
    "bad-trend.csv": SCANLINE.replace("# trend: 0.000000", "# trend: north"),
    "dip-200.csv": SCANLINE.replace("1.4904,61.52", "1.4904,200.0"),
    "text-dip.csv": SCANLINE.replace("1.4904,61.52", "1.4904,steep"),
    "negative-distance.csv": SCANLINE.replace("1.4904,61.52", "-1.4904,61.52"),
    "decreasing.csv": SCANLINE.replace("1.4904,61.52", "29.9,61.52"),
    "nan-dip.csv": SCANLINE.replace("1.4904,61.52", "1.4904,nan"),
    "huge-field.csv": SCANLINE.replace("1.4904,61.52", '"' + "1" * 200_000 + '",61.52'),
    "ragged.csv": SCANLINE.replace("1.4904,61.52,200.35", "1.4904,61.52"),
    "wrong-header.csv": SCANLINE.replace("distance_m", "distanse_m"),
}


def _check(tmp_path: Path, capsys, args: list[str], path: Path) -> None:
    out = tmp_path / "out"
    code = main([*args, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert path.name in err and "Traceback" not in err
    assert not out.exists() and not any(p.name.startswith(".out") for p in tmp_path.iterdir())


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # overflow warnings of the bad numbers
@pytest.mark.parametrize("command", ["boxcount", "traces"])
@pytest.mark.parametrize("name", sorted(TRACE_FILES))
def test_bad_trace_files_exit_2_naming_the_file_and_write_nothing(tmp_path, capsys, command, name):
    path = tmp_path / name
    path.write_bytes(TRACE_FILES[name])
    _check(tmp_path, capsys, [command, str(path)], path)


@pytest.mark.parametrize("name", sorted(SCANLINE_FILES))
def test_bad_scanlines_exit_2_naming_the_file_and_write_nothing(tmp_path, capsys, name):
    path = tmp_path / name
    path.write_text(SCANLINE_FILES[name], encoding="utf-8")
    _check(tmp_path, capsys, ["scanline", str(path)], path)


@pytest.mark.parametrize("command", ["boxcount", "traces", "scanline"])
def test_a_missing_file_or_a_folder_exits_2_naming_it(tmp_path, capsys, command):
    for path in (tmp_path / "missing.csv", tmp_path / "folder.csv"):
        if path.name == "folder.csv":
            path.mkdir()
        _check(tmp_path, capsys, [command, str(path)], path)
