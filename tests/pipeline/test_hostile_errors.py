"""Every error path classified (issue 18, items 1, 4, 5 and 6): bad input exits 2 naming the file
(and the field), an internal failure exits 1 with a diagnostic, never a traceback without --debug;
config-named files are not echoed; images above the pixel limit are refused from their header;
``# frame:`` comments parse in linear time.

Oracles: the exit code, and the message naming what the test wrote (the file, the field, the size
and limit); the input's bytes for what must not be echoed; wall time against a bound with a wide
margin for the linear parser.
"""

from __future__ import annotations

import json
import struct
import time
import zlib
from pathlib import Path

import pytest

from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
SCANLINE = SAMPLES / "quickstart_scanline.csv"
TRACES = SAMPLES / "face_traces.geojson"


def _fails(args, capsys, code: int, *fragments: str) -> str:
    assert main(args) == code
    err = capsys.readouterr().err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    assert "Traceback" not in err
    return err


def _feature(coordinates) -> dict:
    return {"type": "Feature", "properties": {},
            "geometry": {"type": "LineString", "coordinates": coordinates}}


# ------------------------------------------------------------------- data errors are bad input


def test_json_nested_too_deeply_exits_2_naming_the_file(tmp_path, capsys):
    path = tmp_path / "deep.geojson"
    path.write_text("[" * 100_000 + "]" * 100_000)
    for command in ("boxcount", "traces"):
        _fails([command, str(path)], capsys, 2, str(path), "nested too deeply")


def test_csv_field_over_the_csv_modules_limit_exits_2_naming_the_file(tmp_path, capsys):
    path = tmp_path / "survey.csv"
    text = SCANLINE.read_text()
    first = text.splitlines()[7].split(",")[0]  # the first data row's distance
    path.write_text(text.replace(first + ",", '"' + "1" * 200_000 + '",', 1))
    _fails(["scanline", str(path)], capsys, 2, str(path), "not a readable CSV table")


def test_non_utf8_scanline_exits_2_naming_the_file(tmp_path, capsys):
    path = tmp_path / "latin1.csv"
    path.write_bytes(SCANLINE.read_bytes().replace(b"\n", b" caf\xe9\n", 3))
    _fails(["scanline", str(path)], capsys, 2, str(path), "not UTF-8")


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the overflow warnings the CLI shows
def test_svd_that_does_not_converge_exits_2_naming_the_file(tmp_path, capsys):
    path = tmp_path / "huge.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [
        _feature([[0, 0], [1e308, 1e308]]), _feature([[0, 1], [1, 0]])]}))
    _fails(["traces", str(path)], capsys, 2, str(path))


def test_config_nested_too_deeply_exits_2_naming_the_config(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    for command in ("blocks", "solve", "study"):
        _fails([command, str(path), "--out", str(tmp_path / "o")], capsys, 2, str(path),
               "nested too deeply")
    assert not (tmp_path / "o").exists()


def _geos_error():
    from shapely.errors import GEOSException

    return GEOSException("TopologyException: side location conflict at 1 2")


def _cv2_error():
    import cv2

    return cv2.error("OpenCV(4.x) error: (-215:Assertion failed) !_src.empty() in function 'cvtColor'")


@pytest.mark.parametrize("make", [lambda: OverflowError("int too large to convert to float"),
                                  _geos_error, _cv2_error,
                                  lambda: RecursionError("maximum recursion depth exceeded")],
                         ids=["overflow", "geos", "opencv", "recursion"])
def test_library_errors_raised_by_a_files_content_exit_2_naming_it(tmp_path, capsys, monkeypatch,
                                                                    make):
    from rockmass import dfn

    def fails(*args, **kwargs):
        raise make()

    monkeypatch.setattr(dfn, "trace_map_statistics", fails)  # processing the user's trace map
    _fails(["traces", str(TRACES)], capsys, 2, f"{TRACES}: ")


def test_an_internal_failure_exits_1_with_a_diagnostic_and_no_traceback(capsys, monkeypatch):
    from rockmass import dfn

    def bug(*args, **kwargs):
        return {}["no such key"]

    monkeypatch.setattr(dfn, "trace_map_statistics", bug)
    _fails(["traces", str(TRACES)], capsys, 1, "KeyError", "'no such key'", "--debug")
    with pytest.raises(KeyError):
        main(["--debug", "traces", str(TRACES)])


def test_out_of_memory_says_so(capsys, monkeypatch):
    from rockmass import dfn

    def too_big(*args, **kwargs):
        raise MemoryError()

    monkeypatch.setattr(dfn, "trace_map_statistics", too_big)
    _fails(["traces", str(TRACES)], capsys, 1, "out of memory")


# ------------------------------------------------------- files named by a config are not echoed


SECRET = "root:x:0:0:very-secret-line:/root:/bin/bash\n"


@pytest.fixture
def secret(tmp_path) -> Path:
    folder = tmp_path / "private" / "etc"
    folder.mkdir(parents=True)
    path = folder / "passwd"
    path.write_text(SECRET + "daemon:x:1:1\n")
    return path


def test_a_config_naming_any_file_does_not_echo_its_content(tmp_path, capsys, secret):
    config = tmp_path / "configs" / "run.toml"
    config.parent.mkdir()
    config.write_text('[run]\nscanline = "../private/etc/passwd"\n')
    err = _fails(["run", str(config), "--out", str(tmp_path / "out")], capsys, 2,
                 f"{config}: run.scanline: passwd:")
    assert "very-secret" not in err and "root:x" not in err and "private" not in err
    assert not (tmp_path / "out").exists()  # refused while planning, before any stage


def test_a_dfn_fit_naming_any_file_does_not_echo_its_content(tmp_path, capsys, secret):
    text = (SAMPLES / "dfn_fit_seed001.toml").read_text()
    text = text.replace('"scanline_seed001_x.csv", "scanline_seed001_y.csv"',
                        json.dumps(str(secret)))
    config = tmp_path / "fit.toml"
    config.write_text(text)
    err = _fails(["dfn", str(config), "--out", str(tmp_path / "out")], capsys, 2,
                 f"{config}: dfn.fit.scanlines[0]: passwd:")
    assert "very-secret" not in err and "root:x" not in err and "private" not in err


def test_run_finds_a_broken_scanline_before_any_stage_runs(tmp_path, capsys):
    broken = tmp_path / "survey.csv"
    broken.write_text(SCANLINE.read_text().replace("distance_m", "distanse_m"))
    config = tmp_path / "run.toml"
    config.write_text(f'[run]\ntraces = {json.dumps(str(TRACES))}\nscanline = "survey.csv"\n')
    _fails(["run", str(config), "--out", str(tmp_path / "out")], capsys, 2,
           f"{config}: run.scanline: survey.csv:")
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------- pixel limit, from the header


def _png_header_only(path: Path, width: int, height: int) -> Path:
    """A PNG whose header says width x height and whose data is empty: decoding would need
    width * height bytes, reading the header 33."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b""))
                     + chunk(b"IEND", b""))
    return path


@pytest.mark.parametrize("command", [["boxcount"], ["extract", "--m-per-px", "0.01"]])
def test_an_image_above_the_pixel_limit_is_refused_before_decoding(tmp_path, capsys, monkeypatch,
                                                                   command):
    import cv2
    from PIL import Image, ImageFile

    from rockmass.fractal import image as fractal_image

    def no_decoding(*args, **kwargs):
        raise AssertionError("the image was decoded")

    # the header may be read (Image.open is lazy); the pixels must not be
    monkeypatch.setattr(ImageFile.ImageFile, "load", no_decoding)
    monkeypatch.setattr(Image.Image, "load", no_decoding)
    monkeypatch.setattr(cv2, "imdecode", no_decoding)
    monkeypatch.setattr(fractal_image, "read_image", no_decoding, raising=False)
    path = _png_header_only(tmp_path / "bomb.png", 30_000, 20_000)
    out = tmp_path / "out"
    _fails([command[0], str(path), *command[1:], "--out", str(out)], capsys, 2, str(path),
           "30000 x 20000 pixels (600.0 MP)", "limit of 100 MP", "--max-pixels",
           "ROCKMASS_MAX_PIXELS")
    assert not out.exists()


def test_the_pixel_limit_is_raised_by_the_option_and_the_environment(tmp_path, capsys, monkeypatch):
    path = _png_header_only(tmp_path / "wide.png", 5_000, 4_000)  # 20 MP
    _fails(["boxcount", str(path), "--max-pixels", "1e7"], capsys, 2, "limit of 10 MP")
    monkeypatch.setenv("ROCKMASS_MAX_PIXELS", "1e6")
    _fails(["boxcount", str(path)], capsys, 2, "limit of 1 MP")
    # raised above the size: the header check passes and the (empty) data is what fails now
    err = _fails(["boxcount", str(path), "--max-pixels", "2e7"], capsys, 2, str(path))
    assert "above the limit" not in err
    monkeypatch.setenv("ROCKMASS_MAX_PIXELS", "lots")
    _fails(["boxcount", str(path)], capsys, 2, "ROCKMASS_MAX_PIXELS", "'lots'")


def test_extract_with_a_raised_limit_is_not_stopped_by_pillows_own_guard(tmp_path, capsys):
    """A 225 MP header (above Pillow's default bomb limit of ~179 MP) with --max-pixels 3e8: the
    header check passes and Pillow must not refuse it as a bomb (exit 1); the empty data is what
    fails, as bad input (exit 2 naming the file)."""
    path = _png_header_only(tmp_path / "huge.png", 15_000, 15_000)
    err = _fails(["extract", str(path), "--out", str(tmp_path / "out"), "--max-pixels", "3e8"],
                 capsys, 2, str(path))
    assert "bomb" not in err.lower() and "above the limit" not in err


def test_image_size_reads_png_jpeg_tiff_and_bmp_headers(tmp_path):
    import numpy as np
    from PIL import Image

    from rockmass.image_limits import image_size

    pixels = np.zeros((37, 53), np.uint8)  # 53 wide, 37 high
    for name, options in [("a.png", {}), ("a.jpg", {}), ("p.jpg", {"progressive": True}),
                          ("a.tif", {}), ("z.tif", {"compression": "tiff_lzw"}), ("a.bmp", {}),
                          ("big.tif", {"big_tiff": True})]:
        Image.fromarray(pixels).save(tmp_path / name, **options)
        assert image_size(tmp_path / name) == (53, 37), name
    (tmp_path / "junk.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    assert image_size(tmp_path / "junk.png") is None


def test_run_refuses_a_photo_above_the_limit_before_any_stage(tmp_path, capsys):
    _png_header_only(tmp_path / "face.png", 30_000, 30_000)
    config = tmp_path / "run.toml"
    config.write_text('[run]\nphoto = "face.png"\n')
    _fails(["run", str(config), "--out", str(tmp_path / "out")], capsys, 2,
           "run.photo: face.png:", "900.0 MP", "ROCKMASS_MAX_PIXELS")
    assert not (tmp_path / "out").exists()


# -------------------------------------------------------------- linear-time header comments


def _trace_csv(path: Path, frame_line: str) -> Path:
    path.write_text(frame_line + "\ntrace_id,x,y\n1,0,0\n1,1,1\n2,0,1\n2,1,0\n")
    return path


def test_a_1mb_frame_comment_parses_in_linear_time(tmp_path):
    from rockmass.dfn import read_traces

    path = _trace_csv(tmp_path / "t.csv", "# frame: face" + " " * 1_000_000 + "x")
    t0 = time.perf_counter()
    trace_map = read_traces(path)
    elapsed = time.perf_counter() - t0
    assert trace_map.frame.startswith("face") and trace_map.frame.endswith("x")
    assert elapsed < 1.0, f"{elapsed:.2f} s for a 1 MB comment line (quadratic: about an hour)"


@pytest.mark.parametrize("line, frame", [("# frame: face", "face"), ("#frame:face", "face"),
                                         ("  # FRAME :  face  ", "face"),
                                         ("# frame: my face map\t", "my face map")])
def test_frame_comments_keep_their_value(tmp_path, line, frame):
    from rockmass.dfn import read_traces

    try:
        assert read_traces(_trace_csv(tmp_path / "t.csv", line)).frame == frame
    except ValueError as exc:  # a frame name the map refuses: then the value must be the one read
        assert frame in str(exc)


@pytest.mark.parametrize("command", ["boxcount", "traces"])
def test_a_file_name_with_mathtext_does_not_break_the_plot_title(tmp_path, capsys, command):
    path = tmp_path / "a$\\frac{$b.geojson"
    path.write_bytes(TRACES.read_bytes())
    out = tmp_path / "out"
    assert main([command, str(path), "--out", str(out)]) == 0
    assert len(list(out.glob("*.png"))) == 2 - (command == "boxcount")


def test_run_finds_an_unknown_excavation_name_before_any_stage_runs(tmp_path, capsys):
    from .test_run import _config_text

    config = tmp_path / "run.toml"
    config.write_text(_config_text().replace('excavate = ["tunnel"]', 'excavate = ["tunel"]'))
    _fails(["run", str(config), "--out", str(tmp_path / "out")], capsys, 2,
           f"{config}: solve.stages[1].excavate", "unknown excavation stage 'tunel'", "'tunnel'")
    assert not (tmp_path / "out").exists()


def test_run_finds_a_broken_dfn_fit_scanline_before_any_stage_runs(tmp_path, capsys):
    from .test_run import _config_text

    broken = tmp_path / "survey.csv"
    broken.write_text(SCANLINE.read_text().replace("distance_m", "distanse_m"))
    text = _config_text()
    config = tmp_path / "run.toml"
    config.write_text(text.replace('scanlines = ["@scanline"]', 'scanlines = ["survey.csv"]'))
    assert 'scanlines = ["survey.csv"]' in config.read_text()
    _fails(["run", str(config), "--out", str(tmp_path / "out")], capsys, 2,
           f"{config}: dfn.fit.scanlines[0]: survey.csv:")
    assert not (tmp_path / "out").exists()


def test_a_broken_roi_file_is_named_not_the_photo(tmp_path, capsys):
    roi = tmp_path / "deep.geojson"
    roi.write_text("[" * 100_000 + "]" * 100_000)
    photo = SAMPLES / "quickstart_face.png"
    err = _fails(["extract", str(photo), "--m-per-px", "0.01", "--roi", str(roi), "--out",
                  str(tmp_path / "out")], capsys, 2, f"{roi}: --roi: nested too deeply")
    assert str(photo) not in err and not (tmp_path / "out").exists()
