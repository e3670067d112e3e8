"""Infinite extraction settings in a config file ([imaging.params] min_trace_contrast = -inf, the
documented way to turn the contrast filter off): read, hashed, run and written as JSON."""

import json
import math

import cv2
import numpy as np
import pytest

from rockmass.canonical import canonical_json, config_hash
from rockmass.cli import main as cli
from rockmass.config import load_config
from rockmass.errors import ConfigError


def _config(tmp_path, text, name="c.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_infinite_settings_are_read_and_hashed_apart(tmp_path):
    off = load_config(_config(tmp_path, "[imaging.params]\nmin_trace_contrast = -inf\n"))
    assert off.imaging.params["min_trace_contrast"] == -math.inf
    fixed = load_config(_config(tmp_path, "[imaging.params]\nface_contrast_share = inf\n", "f.toml"))
    assert '"min_trace_contrast":"-inf"' in canonical_json(off)
    assert '"face_contrast_share":"inf"' in canonical_json(fixed)
    both = load_config(_config(tmp_path, "[imaging.params]\nmin_trace_contrast = -inf\n"
                                         "face_contrast_share = inf\n", "b.toml"))
    assert len({config_hash(off), config_hash(fixed), config_hash(both)}) == 3
    # max_megapixels = inf (full resolution, as ExtractParams documents) is a config value too
    full = load_config(_config(tmp_path, "[imaging.params]\nmax_megapixels = inf\n", "m.toml"))
    assert full.imaging.params["max_megapixels"] == math.inf


@pytest.mark.parametrize("text, message", [
    ("min_trace_contrast = inf\n", "params.min_trace_contrast must be a number <= 1"),
    ("prob_low = nan\n", "params.prob_low must be a probability in 0-1, got nan"),
    ("link_gap_px = inf\n", "params.link_gap_px must be a finite number >= 0, got inf"),
])
def test_infinities_and_nan_where_a_setting_cannot_take_them_are_refused(text, message, tmp_path):
    path = _config(tmp_path, "[imaging.params]\n" + text)
    with pytest.raises(ConfigError, match="imaging.params") as error:
        load_config(path)
    assert message in str(error.value) and str(path) in str(error.value)


def test_extract_with_the_contrast_filter_off_keeps_bright_lines_and_writes_json(tmp_path):
    face = np.full((200, 260), 110, np.uint8)
    face += np.random.default_rng(1).integers(0, 12, face.shape, dtype=np.uint8)
    for row in (50, 100, 150):  # bright lines: their contrast 1 - I/med is negative
        cv2.line(face, (5, row), (255, row + 20), 200, 3)
    photo = tmp_path / "bright.png"
    cv2.imwrite(str(photo), face)
    config = _config(tmp_path, '[imaging.params]\ndetector = "ridge"\nline_polarity = "bright"\n'
                               "min_trace_contrast = -inf\nface_contrast_share = inf\n")
    assert cli(["extract", str(photo), "--m-per-px", "0.01", "--config", str(config),
                "--out", str(tmp_path / "out"), "--json"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    params = summary["extraction"]["params"]
    assert params["min_trace_contrast"] == "-inf" and float(params["min_trace_contrast"]) == -math.inf
    assert params["face_contrast_share"] == "inf"
    assert summary["extraction"]["n_traces"] >= 3
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["config"]["imaging"]["params"]["min_trace_contrast"] == "-inf"
