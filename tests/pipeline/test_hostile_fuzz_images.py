"""Table-driven bad inputs for ``rockmass extract`` (issue 18, "done when"): at least 20 photos,
regions of interest, scales and configs a user could hand over by mistake.

Each row writes its bad input beside a good photo (a 150 x 225 px synthetic face at 0.04 m/px:
image files that are empty, truncated, text or GIF behind a photo's suffix, a header claiming
10⁶ x 10⁶ pixels, too small to hold a joint, a folder; --roi files that are missing, empty,
not a polygon or outside the photo; scales and widths that are zero, negative, NaN or wider than the
photo; an [imaging] config with bad keys).

Oracles (docs/design.md §4): exit code 2; stderr names the offending file (the photo, the --roi
file or the config with its key path) and says what was expected; no traceback; a fresh --out is
not created and an --out holding the good photo's complete output set is left byte for byte
(:func:`.test_hostile_fuzz_configs.refused`).
"""

from __future__ import annotations

import json
import struct
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from rockmass.cli import main

from .test_hostile_errors import _png_header_only
from .test_hostile_fuzz_configs import refused

M_PER_PX = "0.04"


@pytest.fixture(scope="module")
def face(tmp_path_factory) -> Path:
    """A good photo (150 x 225 px, 0.04 m/px: a 9 m x 6 m face)."""
    from rockmass.imaging import save_synthetic_face, synthetic_face

    face = synthetic_face("easy", seed=11, shape_px=(150, 225), m_per_px=0.04)
    return Path(save_synthetic_face(face, tmp_path_factory.mktemp("face"))["image"])


@pytest.fixture(scope="module")
def good_set(face, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("good-extract") / "out"
    assert main(["extract", str(face), "--m-per-px", M_PER_PX, "--out", str(out)]) == 0
    return out


def _image(path: Path, pixels: np.ndarray, **options) -> Path:
    from PIL import Image

    Image.fromarray(pixels).save(path, **options)
    return path


def _grey(shape=(150, 225)) -> np.ndarray:
    pixels = np.full(shape, 200, np.uint8)
    pixels[shape[0] // 2, :] = 20
    return pixels


def _polygon(path: Path, ring, kind: str = "Polygon") -> Path:
    coordinates = [ring] if kind == "Polygon" else ring
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": kind,
                                                           "coordinates": coordinates}}]}))
    return path


def _truncated_jpeg(path: Path, face: Path) -> Path:
    whole = _image(path.with_name("whole.jpg"), _grey())
    path.write_bytes(whole.read_bytes()[:300])
    return path


def _truncated_png(path: Path, face: Path) -> Path:
    path.write_bytes(face.read_bytes()[:400])
    return path


def _png_bad_data(path: Path, face: Path) -> Path:
    """The good photo with 16 bytes of its first data chunk zeroed (its checksum now wrong)."""
    data = bytearray(face.read_bytes())
    at = data.index(b"IDAT") + 8  # inside the first data chunk
    data[at:at + 16] = bytes(16)
    path.write_bytes(bytes(data))
    return path


# A row: name -> (make, expected). ``make(folder, face)`` writes the bad input and returns
# (arguments after "extract", the offending file); ``expected`` is what the message must say.
Make = Callable[[Path, Path], tuple[list, Path]]


def photo(write: Callable[[Path, Path], Path], name: str) -> Make:
    """A bad photo ``name`` (written by ``write(path, face)``), with a good scale."""
    def make(folder: Path, face: Path):
        path = write(folder / name, face)
        return [str(path), "--m-per-px", M_PER_PX], path
    return make


def flags(*args: str) -> Make:
    """The good photo with bad options."""
    def make(folder: Path, face: Path):
        return [str(face), *args], face
    return make


def roi(write: Callable[[Path], Path | None], name: str = "roi.geojson",
    flag: str = "--roi") -> Make:
    """The good photo with a bad region-of-interest file."""
    def make(folder: Path, face: Path):
        path = folder / name
        write(path)
        return [str(face), "--m-per-px", M_PER_PX, flag, str(path)], path
    return make


def config(text: str) -> Make:
    """The good photo with a bad [imaging] config."""
    def make(folder: Path, face: Path):
        path = folder / "site.toml"
        path.write_text(text)
        return [str(face), "--config", str(path)], path
    return make


def _bytes(data: bytes):
    return lambda path, face=None: (path.write_bytes(data), path)[1]


CASES = {
    "empty-png": (photo(_bytes(b""), "face.png"),
                  "not a readable image (JPEG, PNG or TIFF expected)"),
    "truncated-png": (photo(_truncated_png, "face.png"),
                      "could not be decoded (truncated or corrupt?)"),
    "truncated-jpeg": (photo(_truncated_jpeg, "face.jpg"),
                       "could not be decoded (truncated or corrupt?)"),
    "text-as-png": (photo(_bytes(b"joint traces: see notebook p. 12\n"), "face.png"),
                    "not a readable image (JPEG, PNG or TIFF expected)"),
    "pdf-as-jpeg": (photo(_bytes(b"%PDF-1.4\n1 0 obj << /Type /Catalog >> endobj\n%%EOF\n"),
                          "face.jpg"), "not a readable image (JPEG, PNG or TIFF expected)"),
    "png-bad-data": (photo(_png_bad_data, "face.png"),
                     "could not be decoded (truncated or corrupt?)"),
    "header-1e6-squared": (photo(lambda p, f: _png_header_only(p, 10**6, 10**6), "face.png"),
                           "above the limit of 100 MP read before decoding"),
    "one-pixel": (photo(lambda p, f: _image(p, np.zeros((1, 1), np.uint8)), "face.png"),
                  "at least 16 x 16 are needed"),
    "one-row": (photo(lambda p, f: _image(p, np.zeros((1, 400), np.uint8)), "face.png"),
                "at least 16 x 16 are needed"),
    "constant-16-bit": (photo(lambda p, f: _image(p, np.zeros((150, 225), np.uint16)),
                              "face.png"), "image is blank"),
    # was "face.png: no such file"
    "folder": (photo(lambda p, f: (p.mkdir(), p)[1], "face.png"), "a folder, not a photograph"),
    "missing": (photo(lambda p, f: p, "face.png"), "no such file"),
    "joint-width-zero": (flags("--m-per-px", M_PER_PX, "--joint-width", "0"),
                         "joint_width_px must be a finite width > 0"),
    "joint-width-nan": (flags("--m-per-px", M_PER_PX, "--joint-width", "nan"),
                        "joint_width_px must be a finite width > 0"),
    "m-per-px-zero": (flags("--m-per-px", "0"), "m_per_px must be a finite scale > 0"),
    "m-per-px-inf": (flags("--m-per-px", "inf"), "m_per_px must be a finite scale > 0"),
    "control-points-same": (flags("--control-points", "10", "10", "10", "10", "2.0"),
                            "control_points.rc_px: the two points coincide"),
    # was accepted (exit 0): a scale from a point 8850 rows below the photo
    "control-points-outside": (flags("--control-points", "10", "10", "9000", "10", "2.0"),
                               "control_points.rc_px: point 2 (row 9000, col 10) lies outside "
                               "the 150 x 225 pixel image"),
    "face-dip-120": (flags("--m-per-px", M_PER_PX, "--face-dip", "120",
                           "--face-dip-direction", "0"), "face_dip_deg must be in 0-90 degrees"),
    "sets-zero": (flags("--m-per-px", M_PER_PX, "--sets", "0"), "n_sets must be >= 1"),
    "roi-missing": (roi(lambda p: None), "cannot read the --roi file"),
    "roi-empty": (roi(lambda p: p.write_bytes(b"")), "invalid JSON"),
    "roi-line": (roi(lambda p: _polygon(p, [[0, 0], [5, 5]], "LineString")),
                 "holds no polygon (a GeoJSON Polygon feature is expected)"),
    # was named after the photo, not the --roi file
    "roi-outside": (roi(lambda p: _polygon(p, [[100, 100], [110, 100], [110, 110], [100, 100]])),
                    "--roi: roi lies outside the 150 x 225 image"),
    "roi-px-collinear": (roi(lambda p: _polygon(p, [[0, 0], [10, 10], [20, 20], [0, 0]]),
                             flag="--roi-px"), "encloses zero area"),
    "config-unknown-key": (config("[imaging]\nm_per_px = 0.04\nwidth_px = 3\n"),
                           "imaging.width_px: unknown key (allowed: "),
    "config-negative-scale": (config("[imaging]\nm_per_px = -0.04\n"),
                              "imaging.m_per_px: must be > 0"),
    "config-malformed": (config("[imaging\nm_per_px = 0.04\n"), "invalid TOML"),
}


def test_extract_has_at_least_20_bad_inputs():
    assert len(CASES) >= 20


@pytest.mark.parametrize("name", list(CASES))
def test_a_bad_photo_or_option_exits_2_naming_the_file_and_writes_nothing(tmp_path, capsys, face,
                                                                          good_set, name):
    make, expected = CASES[name]
    args, named = make(tmp_path, face)
    refused(tmp_path, capsys, ["extract", *args], [f"{named}: ", expected], good_set)
