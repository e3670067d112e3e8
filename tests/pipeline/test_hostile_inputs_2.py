"""Hostile and broken inputs, continued (issue 18): GeoJSON features named in every error, a study's
``[solve]`` files and a run's later-stage files read before anything runs, budgets for blocks3d and
study, ``rockmass dfn`` on a file of several stages, stage config hashes independent of --out.

Oracles: the exit code and the message naming the file, the field (or feature) and what was
expected; that --out is not created (nothing half-written); for the dfn command, the realization of
the same ``[dfn]`` alone in a file (byte-identical fractures.csv); for the hashes, the same run to
two folders.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rockmass.cli import main

from .test_cli_dfn import CONFIG as DFN_CONFIG
from .test_hostile_errors import _fails

WINDOW = {"type": "Feature", "properties": {"role": "window"},
          "geometry": {"type": "Polygon",
                       "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}}
GOOD = {"type": "Feature", "properties": {"id": "A"},
        "geometry": {"type": "LineString", "coordinates": [[1, 1], [8, 2]]}}


def _geojson(path: Path, feature_text: str) -> Path:
    """A map of a good trace, the feature given as JSON text (feature 1) and the window."""
    path.write_text('{"type": "FeatureCollection", "features": [' + json.dumps(GOOD) + ", "
                    + feature_text + ", " + json.dumps(WINDOW) + "]}")
    return path


def _line(coordinates: str, fid: str = "B") -> str:
    return ('{"type": "Feature", "properties": {"id": "%s"}, "geometry": {"type": "LineString", '
            '"coordinates": %s}}' % (fid, coordinates))


# ------------------------------------------------------------- GeoJSON: the feature is named


@pytest.mark.parametrize("feature, expected", [
    (_line("[[1, 1], [NaN, 2]]"), "feature 1 (id=B): coordinates contain NaN/Infinity at positions [1]"),
    (_line("[[1, 1], [2, Infinity]]"), "feature 1 (id=B): coordinates contain NaN/Infinity"),
    (_line("[[1, 1]]"), "feature 1 (id=B): coordinates has 1 position(s); a trace needs at least 2"),
    ('{"type": "Feature", "properties": {"id": "B"}, "geometry": {"type": "LineString"}}',
     "feature 1 (id=B): coordinates: expected a list of [x, y] positions, got null"),
    ('{"type": "Feature", "properties": {"id": "B"}, "geometry": {"type": "Point", '
     '"coordinates": [1, 1]}}', "feature 1 (id=B): geometry type 'Point' is not a trace"),
    # these three were accepted or named no feature
    (_line("[[1, 1], [true, 2]]"), "feature 1 (id=B): coordinates[1]: expected a position [x, y]"),
    (_line("[[1, 1], [1" + "0" * 400 + ", 2]]"),
     "feature 1 (id=B): coordinates beyond ±1e+12 m at positions [1]"),
    (_line("[[1, 1], [1e300, 2]]"), "feature 1 (id=B): coordinates beyond ±1e+12 m at positions [1]"),
], ids=["nan", "inf", "one-point", "no-coordinates", "point", "bool", "huge-int", "huge-float"])
def test_a_bad_geojson_feature_exits_2_naming_the_file_and_feature(tmp_path, capsys, feature,
                                                                  expected):
    path = _geojson(tmp_path / "map.geojson", feature)
    out = tmp_path / "out"
    _fails(["traces", str(path), "--out", str(out)], capsys, 2, f"{path}: {expected}")
    assert not out.exists()


def test_a_trace_far_beyond_any_map_does_not_cut_blocks_silently(tmp_path, capsys):
    """A trace at 1e300 m gave overflow warnings and a block model without it (exit 0)."""
    _geojson(tmp_path / "far.geojson", _line("[[1, 1], [1e300, 2]]"))
    cfg = tmp_path / "blocks.toml"
    cfg.write_text('[blocks]\ntraces = "far.geojson"\n[blocks.domain]\nwidth_m = 12.0\n'
                   "height_m = 12.0\n")
    _fails(["blocks", str(cfg), "--out", str(tmp_path / "out")], capsys, 2,
           f"{cfg}: blocks.traces: far.geojson: feature 1 (id=B): coordinates beyond ±1e+12 m")
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------- dfn: a file of several stages


def test_dfn_runs_the_dfn_section_of_a_file_with_other_stages(tmp_path):
    """``rockmass dfn samples/blocks_dfn_section.toml`` exited 2 ("blocks: unknown key"): one
    file may hold several stages, each command reads its own section (as rockmass blocks does)."""
    alone = tmp_path / "dfn.toml"
    alone.write_text(DFN_CONFIG.replace("realizations = 3", "realizations = 1"))
    both = tmp_path / "both.toml"
    both.write_text(alone.read_text() + "\n[blocks]\n[blocks.domain]\nwidth_m = 8.0\n"
                    "height_m = 8.0\n[blocks.two_sets]\nalpha_deg = 30.0\ntheta_deg = 60.0\n"
                    "spacing_m = [3.0, 4.0]\n")
    assert main(["dfn", str(alone), "--out", str(tmp_path / "a")]) == 0
    assert main(["dfn", str(both), "--out", str(tmp_path / "b")]) == 0
    csv = "realization_0000/fractures.csv"
    assert (tmp_path / "a" / csv).read_bytes() == (tmp_path / "b" / csv).read_bytes()
    manifests = [json.loads((tmp_path / d / "manifest.json").read_text()) for d in "ab"]
    assert manifests[0]["config_hash"] == manifests[1]["config_hash"]
    assert set(manifests[1]["config"]) == {"dfn"}


def test_dfn_on_a_file_without_dfn_exits_2_naming_the_section(tmp_path, capsys):
    cfg = tmp_path / "blocks.toml"
    cfg.write_text("[blocks]\n[blocks.domain]\nwidth_m = 8.0\nheight_m = 8.0\n[blocks.two_sets]\n"
                   "alpha_deg = 30.0\ntheta_deg = 60.0\nspacing_m = [3.0, 4.0]\n")
    _fails(["dfn", str(cfg), "--out", str(tmp_path / "o")], capsys, 2,
           f"{cfg}: dfn: required section is missing")
    assert not (tmp_path / "o").exists()


def test_dfn_names_a_bad_key_of_another_section(tmp_path, capsys):
    cfg = tmp_path / "both.toml"
    cfg.write_text(DFN_CONFIG + "\n[blocks]\nseeed = 1\n")
    _fails(["dfn", str(cfg), "--out", str(tmp_path / "o")], capsys, 2, f"{cfg}: blocks.seeed")
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------- run: config hashes independent of --out


def test_stage_config_hashes_do_not_depend_on_the_out_folder(tmp_path):
    """blocks.traces = "@traces" of a photo names the extract stage's traces.geojson inside --out:
    the blocks stage's manifest hashed that absolute path, so the same run to another folder gave
    another config_hash (issue 18). Now the run's own outputs are recorded as ``<run>/...``."""
    from rockmass.imaging import save_synthetic_face, synthetic_face

    face = synthetic_face("easy", seed=11, shape_px=(150, 225), m_per_px=0.04)
    photo = save_synthetic_face(face, tmp_path)["image"]
    cfg = tmp_path / "run.toml"
    cfg.write_text(f'[run]\nphoto = "{Path(photo).name}"\nstages = ["blocks"]\n'
                   "[imaging]\nm_per_px = 0.04\n"
                   '[blocks]\ntraces = "@traces"\n[blocks.domain]\nwidth_m = 9.0\nheight_m = 6.0\n')
    hashes = []
    for out in (tmp_path / "one", tmp_path / "deeper" / "two"):
        assert main(["run", str(cfg), "--out", str(out)]) == 0
        hashes.append({stage: json.loads((out / stage / "manifest.json").read_text())["config_hash"]
                       for stage in ("extract", "blocks")})
        recorded = json.loads((out / "blocks" / "manifest.json").read_text())["config"]
        assert recorded["blocks"]["traces"] == "<run>/extract/traces.geojson"
    assert hashes[0] == hashes[1]


# ----------------------------------------------- run: every stage's files read before the first


SLIPS = [("A", [[1, 1], [8, 2]]), ("C", [[1, 7], [9, 6]]), ("E", [[5, 1], [5, 9]])]

BLOCKS = """[blocks]
[blocks.domain]
width_m = 12.0
height_m = 12.0
origin_xy_m = [-6.0, -6.0]
[blocks.two_sets]
alpha_deg = 30.0
theta_deg = 60.0
spacing_m = [3.0, 4.0]
[[blocks.excavations]]
shape = "circle"
name = "tunnel"
center_xy_m = [0.0, 0.0]
radius_m = 2.0
n_sides = 12
"""

SOLVE = """[solve]
blocks_file = "{blocks_file}"
[solve.material]
density_kg_m3 = 2650.0
[solve.joints.default]
model = "coulomb"
kn_pa_m = 1e9
ks_pa_m = 5e8
friction_deg = 30.0
[[solve.fixes]]
where = "bottom"
[[solve.stages]]
name = "equilibrium"
max_steps = 50
[[solve.stages]]
name = "{excavation}"
excavate = ["{excavation}"]
max_steps = 50
"""

SHAKE = """[[solve.stages]]
name = "shake"
kind = "dynamic"
duration_s = 0.01
[[solve.velocity_inputs]]
where = "bottom"
component = "x"
history = {{ type = "csv", file = "{history}" }}
"""


@pytest.fixture(scope="module")
def blocks_json(tmp_path_factory) -> Path:
    """A blocks.json of ``rockmass blocks`` with the excavation "tunnel"."""
    folder = tmp_path_factory.mktemp("blocks")
    (folder / "blocks.toml").write_text(BLOCKS)
    assert main(["blocks", str(folder / "blocks.toml"), "--out", str(folder / "out")]) == 0
    return folder / "out" / "blocks.json"


def _run_config(folder: Path, blocks_file: Path, excavation: str = "tunnel",
                history: str | None = None) -> Path:
    """A run of a trace map (traces, boxcount) and a solve of ``blocks_file``: the solve stage
    comes last, after two stages that would have written their folders."""
    features = [{"type": "Feature", "properties": {"id": n},
                 "geometry": {"type": "LineString", "coordinates": xy}} for n, xy in SLIPS]
    (folder / "map.geojson").write_text(json.dumps({"type": "FeatureCollection",
                                                    "features": features + [WINDOW]}))
    text = '[run]\ntraces = "map.geojson"\n' + SOLVE.format(blocks_file=blocks_file,
                                                             excavation=excavation)
    if history is not None:
        text += SHAKE.format(history=history)
    cfg = folder / "run.toml"
    cfg.write_text(text)
    return cfg


def test_run_reads_a_broken_blocks_file_before_any_stage(tmp_path, capsys):
    broken = tmp_path / "blocks.json"
    broken.write_text('{"domain": [[0, 0], [1, 0]], "secret": "root:x:0:0"}')
    cfg = _run_config(tmp_path, broken)
    out = tmp_path / "out"
    err = _fails(["run", str(cfg), "--out", str(out)], capsys, 2,
                 f"{cfg}: solve.blocks_file: blocks.json: format/version must be 'rockmass.blocks'")
    assert "root:x" not in err
    assert not out.exists()


def test_run_checks_excavation_names_against_the_blocks_file_before_any_stage(
        tmp_path, capsys, blocks_json):
    cfg = _run_config(tmp_path, blocks_json, excavation="cavern")
    out = tmp_path / "out"
    _fails(["run", str(cfg), "--out", str(out)], capsys, 2,
           f"{cfg}: solve.stages[1].excavate: unknown excavation stage 'cavern'", "'tunnel'")
    assert not out.exists()


def test_run_reads_a_broken_history_csv_before_any_stage(tmp_path, capsys, blocks_json):
    (tmp_path / "motion.csv").write_text("time,value\n0,0\n0.01,fast\n")
    cfg = _run_config(tmp_path, blocks_json, history="motion.csv")
    out = tmp_path / "out"
    _fails(["run", str(cfg), "--out", str(out)], capsys, 2,
           f"{cfg}: solve.velocity_inputs[0].history.file: motion.csv: line 3: not a number")
    assert not out.exists()


def test_run_with_good_later_inputs_runs_every_stage(tmp_path, capsys, blocks_json):
    (tmp_path / "motion.csv").write_text("time,value\n0,0\n0.01,0.01\n0.02,0\n")
    cfg = _run_config(tmp_path, blocks_json, history="motion.csv")
    cfg.write_text(cfg.read_text().replace('traces = "map.geojson"',
                                           'traces = "map.geojson"\nstages = ["boxcount", "solve"]'))
    out = tmp_path / "out"
    assert main(["run", str(cfg), "--out", str(out)]) == 0
    assert {s["name"] for s in json.loads((out / "run.json").read_text())["stages"]} == \
        {"boxcount", "solve"}


def test_run_decodes_a_truncated_photo_before_any_stage(tmp_path, capsys):
    """A JPEG cut short passes Pillow's ``verify``: the extract stage found it, after --out was
    made."""
    import numpy as np
    from PIL import Image

    grey = (np.random.default_rng(0).random((200, 300)) * 255).astype(np.uint8)
    Image.fromarray(grey).save(tmp_path / "whole.jpg", quality=90)
    data = (tmp_path / "whole.jpg").read_bytes()
    (tmp_path / "face.jpg").write_bytes(data[:len(data) // 3])
    cfg = tmp_path / "run.toml"
    cfg.write_text('[run]\nphoto = "face.jpg"\n[imaging]\nm_per_px = 0.02\n')
    out = tmp_path / "out"
    _fails(["run", str(cfg), "--out", str(out)], capsys, 2,
           f"{cfg}: run.photo: face.jpg: the image could not be decoded (truncated or corrupt?)")
    assert not out.exists()


# ------------------------------------------------- study: its [solve] files before the first case


def _study(folder: Path, history: str, grid: str = "") -> Path:
    """The study of test_study.py with a dynamic stage shaken by the CSV ``history``."""
    from .test_study import BASE, STUDY

    cfg = folder / "study.toml"
    cfg.write_text(BASE + SHAKE.format(history=history) + STUDY + grid)
    return cfg


def test_study_refuses_a_history_file_that_no_case_can_read(tmp_path, capsys):
    """Every case failed on it, one after the other, and the study wrote them all (exit 1)."""
    cfg = _study(tmp_path, "absent.csv")
    out = tmp_path / "out"
    _fails(["study", str(cfg), "--out", str(out), "--workers", "1"], capsys, 2,
           f"{cfg}: solve.velocity_inputs[0].history.file: absent.csv: no such file, and every "
           "case reads it", "no case has run")
    assert not out.exists()


def test_study_reads_every_cases_history_file_before_any_case_runs(tmp_path, capsys):
    """A grid over the history file, the second broken: the first case's preflight passed, and the
    broken file failed its cases after the others ran."""
    (tmp_path / "good.csv").write_text("time,value\n0,0\n0.01,0.01\n0.02,0\n")
    (tmp_path / "broken.csv").write_text("time,value\n0,0\n0.01,root:x:0:0\n")
    cfg = _study(tmp_path, "good.csv",
                 '"solve.velocity_inputs[0].history.file" = ["good.csv", "broken.csv"]\n')
    out = tmp_path / "out"
    err = _fails(["study", str(cfg), "--out", str(out), "--workers", "1"], capsys, 2,
                 f"{cfg}: solve.velocity_inputs[0].history.file: broken.csv: line 3: not a number",
                 "(study case 2: ", "no case has run")
    assert "root:x" not in err
    assert not out.exists()


def test_study_refuses_a_blocks_file_it_would_not_read(tmp_path, capsys):
    """A study builds each case's blocks from [blocks]: solve.blocks_file was silently ignored."""
    from .test_study import BASE, STUDY

    cfg = tmp_path / "study.toml"
    cfg.write_text(BASE.replace("[solve]\n", '[solve]\nblocks_file = "blocks.json"\n') + STUDY)
    out = tmp_path / "out"
    _fails(["study", str(cfg), "--out", str(out), "--list"], capsys, 2,
           f"{cfg}: solve.blocks_file: a study builds each case's blocks from its [blocks] section")
    assert not out.exists()


# ------------------------------------------------------------------ budgets: blocks3d and study

BLOCKS3D = """[blocks3d]
box_min_m = [0.0, 0.0, 0.0]
box_max_m = [{side}, {side}, {side}]
[[blocks3d.sets]]
dip_deg = 10.0
dip_direction_deg = 120.0
spacing_m = {spacing}
[[blocks3d.sets]]
dip_deg = 80.0
dip_direction_deg = 30.0
spacing_m = 1.0
[[blocks3d.sets]]
dip_deg = 75.0
dip_direction_deg = 300.0
spacing_m = 1.0
"""


def test_a_huge_blocks3d_box_is_refused_naming_the_densest_set(tmp_path, capsys, monkeypatch):
    """A 1 km cube cut by three sets about 1 m apart: about 2e9 pieces (15 TiB) were cut until
    memory ran out."""
    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "16G")
    cfg = tmp_path / "huge.toml"
    cfg.write_text(BLOCKS3D.format(side=1000.0, spacing=0.5))
    out = tmp_path / "out"
    _fails(["blocks3d", str(cfg), "--out", str(out)], capsys, 2,
           f"{cfg}: blocks3d.sets[0].spacing_m: 1 model(s) of about 1.97e+09 pieces",
           "limit of 16 GiB (ROCKMASS_MAX_MEMORY)", "ROCKMASS_MAX_MEMORY=SIZE")
    assert not out.exists()


def test_blocks3d_realizations_of_a_dense_dfn_are_refused_naming_the_set(tmp_path, capsys,
                                                                         monkeypatch):
    from .test_cli_blocks3d import DFN_CONFIG

    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "16G")
    cfg = tmp_path / "dense.toml"
    cfg.write_text(DFN_CONFIG.replace("REALIZATION", "0").replace(
        'intensity = { measure = "P32", value = 0.5 }\n\n[[dfn.sets]]',
        'intensity = { measure = "P32", value = 1000.0 }\n\n[[dfn.sets]]'))
    out = tmp_path / "out"
    _fails(["blocks3d", str(cfg), "--out", str(out), "--realizations", "3"], capsys, 2,
           f"{cfg}: dfn.sets[0].intensity: 3 model(s) of about", "from DFN disks")
    assert not out.exists()


def test_the_blocks3d_estimate_is_the_pieces_cut(tmp_path):
    """The arrangement count 1 + planes + lines + points against the pieces three persistent sets
    cut from a 6 m cube."""
    from rockmass.blockgen.model3d import Blocks3DSettings, build3d
    from rockmass.budgets import block3d_count_terms
    from rockmass.config import load_config
    from rockmass.dfn.orientation import normal_from_dip

    cfg = tmp_path / "small.toml"
    cfg.write_text(BLOCKS3D.format(side=6.0, spacing=1.0))
    settings = load_config(cfg).blocks3d.to_library()
    assert isinstance(settings, Blocks3DSettings)
    built = len(build3d(settings).blocks.pieces)
    terms = block3d_count_terms([settings.box_min_m, settings.box_max_m],
                                [(normal_from_dip(s.dip_deg, s.dip_direction_deg), s.spacing_m)
                                 for s in settings.sets])
    assert 0.8 * built <= 1 + sum(terms.values()) <= 1.25 * built, (built, terms)


def test_a_study_whose_largest_case_overflows_memory_is_refused_before_any_case(
        tmp_path, capsys, monkeypatch):
    """Two workers, each on a case of a 10⁶ m x 12 m domain: up to 1.6e6 blocks each (12 GiB),
    found as MemoryErrors case by case."""
    from .test_hostile_inputs import STUDY as BLOCKS_STUDY

    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "4G")
    cfg = tmp_path / "study.toml"
    cfg.write_text(BLOCKS_STUDY.format(colour_by="blocks.two_sets.theta_deg")
                   + "blocks.domain.width_m = [12.0, 1e6]\n")
    out = tmp_path / "out"
    _fails(["study", str(cfg), "--out", str(out), "--workers", "2"], capsys, 2,
           f"{cfg}: blocks.two_sets.spacing_m: 2 worker(s) at once, each on a case of up to about "
           "1.58e+06 blocks", "(study case 3: theta_deg=90.0, width_m=1000000.0, the largest of 4 "
           "cases to run) need about 12.1 GiB", "limit of 4 GiB (ROCKMASS_MAX_MEMORY)",
           "--workers")
    assert not out.exists()
