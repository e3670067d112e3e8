"""``rockmass study``: cases from a grid / list x realizations, executors, resume, report, bad input."""

from __future__ import annotations

import base64
import csv
import io
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

from rockmass.cli import main

from . import _chromium

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

# a 12 m square with two joint sets and a circular tunnel: about 30 blocks, a few thousand steps
# (step caps high enough for the stages to reach equilibrium, or fail blocks, rather than stop)
BASE = """[blocks]
dangling = "glued"
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

[fractal]
n_offsets = 2

[solve]
[solve.material]
density_kg_m3 = 2650.0
[solve.joints.default]
model = "coulomb"
kn_pa_m = 1e9
ks_pa_m = 5e8
friction_deg = 30.0
[solve.insitu]
syy_pa = 1e6
sxx_pa = 1e6
[[solve.fixes]]
where = "bottom"
dofs = "y"
[[solve.fixes]]
where = "left"
dofs = "x"
[[solve.fixes]]
where = "right"
dofs = "x"
[[solve.boundary_stress]]
sides = ["top"]
from_insitu = true
[[solve.stages]]
name = "equilibrium"
max_steps = 3000
[[solve.stages]]
name = "tunnel"
excavate = ["tunnel"]
max_steps = 5000
"""

STUDY = """
[study]
realizations = 2
seed = 7
[study.grid]
blocks.two_sets.theta_deg = [60.0, 90.0]
"""


def _write(tmp_path, text, name="study.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _rows(path: Path) -> list[dict]:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def _without_time(rows):
    return [{k: v for k, v in r.items() if k != "wall_time_s"} for r in rows]


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("study")
    cfg = _write(tmp, BASE + STUDY)
    out = tmp / "serial"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 0
    return cfg, out


def _rebuild(case_config: Path):
    """A case rebuilt apart from the study, from its cases/<id>/config.toml: (block model, P21 of
    its joint contacts, DEM result). Persistent sets, so every joint segment is a joint contact and
    P21 = joint contact length / domain area, but for the joint between a merged sliver and its
    neighbour and the builder's mm-scale snapping (0.2 % at most on the study's cases)."""
    import tomllib

    from rockmass.blockgen import CONTACT_KINDS
    from rockmass.config import RockmassConfig
    from rockmass.solver import run
    from rockmass.study import _build_model

    doc = RockmassConfig.model_validate(tomllib.loads(case_config.read_text(encoding="utf-8")))
    model = _build_model(doc, case_config)
    x, y = np.asarray(model.domain_xy_m, float).T
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    joint = model.contact_kind == CONTACT_KINDS.index("joint")
    p21 = model.contact_length_m[joint].sum() / area
    return model, p21, run(model, doc.solve.to_settings(model, case_config))


def test_results_one_row_per_case_with_the_measures(serial_run):
    """Every row against its case rebuilt and re-solved apart from the study (the real solver):
    outcome (case_outcome of the run), displacements over the blocks in equilibrium, monitors,
    failed blocks, worst ratio."""
    from rockmass.study import IN_EQUILIBRIUM, MONITOR_COLUMNS, case_outcome

    cfg, out = serial_run
    rows = _rows(out / "results.csv")
    assert [int(r["case"]) for r in rows] == [0, 1, 2, 3]
    assert [float(r["blocks.two_sets.theta_deg"]) for r in rows] == [60.0, 60.0, 90.0, 90.0]
    assert [int(r["realization"]) for r in rows] == [0, 1, 0, 1]
    # common random numbers: realization r has the same seed in every parameter combination
    assert rows[0]["seed"] == rows[2]["seed"] != rows[1]["seed"]
    # the real solver brings the cases to equilibrium, some with keyblocks taken out
    assert any(r["status"] in IN_EQUILIBRIUM for r in rows), [r["error"] for r in rows]
    for r in rows:
        assert r["status"] in IN_EQUILIBRIUM + ("not_converged",), r["error"]
        assert 1.0 < float(r["d_box"]) < 2.0 and 0.9 < float(r["d_box_r2"]) <= 1.0
        # the row's measures are those of the case rebuilt and re-solved apart from the study
        model, p21, result = _rebuild(out / "cases" / r["case_id"] / "config.toml")
        assert int(r["n_blocks"]) == model.n_blocks > 10
        assert int(r["n_contacts"]) == model.n_contacts
        assert float(r["p21_per_m"]) == pytest.approx(p21, rel=5e-3)
        last = result.stages[-1]
        status, reason = case_outcome(result)
        assert r["status"] == status and r["error"] == (reason or "")
        assert float(r["max_displacement_boundary_m"]) \
            == last.max_displacement_boundary_equilibrium_m > 0
        assert float(r["max_displacement_overall_m"]) == last.max_displacement_equilibrium_m
        assert r["max_displacement_m"] == (r["max_displacement_boundary_m"]
                                           if status in IN_EQUILIBRIUM else "")
        for name, column in MONITOR_COLUMNS.items():
            assert r[column] == (repr(float(last.monitors[name])) if name in last.monitors
                                 else "")
        failed = [fb for s in result.stages for fb in s.failed_blocks]
        assert int(r["failed_blocks"]) == len(failed)
        assert float(r["failed_area_m2"]) == pytest.approx(sum(fb["area_m2"] for fb in failed))
        if failed:  # the blocks that kept moving are counted apart, not as a displacement
            assert float(r["max_displacement_m"]) < max(fb["displacement_m"] for fb in failed)
        assert float(r["worst_ratio"]) == max(s.worst_ratio for s in result.stages
                                              if s.kind == "static")
        converged = result.status in IN_EQUILIBRIUM \
            and all(s.converged is not False for s in result.stages)
        assert r["converged"] == ("true" if converged else "false")
        assert r["solve_status"] == result.status
        assert int(r["steps"]) == sum(s.steps for s in result.stages)
        assert float(r["wall_time_s"]) > 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["extra"]["cases"] == 4 and manifest["extra"]["finished"] == 4
    assert manifest["extra"]["executor"] == "serial"
    case = json.loads((out / "cases" / rows[0]["case_id"] / "case.json").read_text())
    assert case["config"]["blocks"]["seed"] == int(rows[0]["seed"])
    assert case["config"]["blocks"]["two_sets"]["theta_deg"] == 60.0


def test_two_local_workers_give_the_same_results_as_serial(serial_run, tmp_path):
    cfg, out = serial_run
    out2 = tmp_path / "pool"
    assert main(["study", str(cfg), "--out", str(out2), "--workers", "2"]) == 0
    assert _without_time(_rows(out2 / "results.csv")) == _without_time(_rows(out / "results.csv"))
    manifest = json.loads((out2 / "manifest.json").read_text())
    assert manifest["extra"]["executor"].startswith("local process pool (2 workers)")
    _assert_one_thread_and_warmed_once(out2, n_workers=2)


def test_rerun_skips_finished_cases_and_reruns_a_missing_one(serial_run, tmp_path, capsys):
    import shutil

    cfg, out = serial_run
    copy = tmp_path / "resume"
    shutil.copytree(out, copy)
    rows = _rows(copy / "results.csv")
    shutil.rmtree(copy / "cases" / rows[2]["case_id"])  # as if killed before case 2 was written
    kept = {r["case_id"]: (copy / "cases" / r["case_id"] / "case.json").read_bytes()
            for r in rows if r is not rows[2]}
    capsys.readouterr()
    assert main(["study", str(cfg), "--out", str(copy), "--workers", "1"]) == 0
    err = capsys.readouterr().err
    assert "3 already finished (skipped), 1 to run" in err
    for cid, content in kept.items():  # untouched
        assert (copy / "cases" / cid / "case.json").read_bytes() == content
    assert _without_time(_rows(copy / "results.csv")) == _without_time(rows)


def test_interrupted_study_resumes_without_losing_cases(serial_run, tmp_path, monkeypatch, capsys):
    import rockmass.study as study

    cfg, out = serial_run
    real = study.run_case
    calls = []

    def interrupted(task):
        if len(calls) == 2:
            raise KeyboardInterrupt
        calls.append(task["case"])
        return real(task)

    monkeypatch.setattr(study, "run_case", interrupted)
    target = tmp_path / "killed"
    assert main(["study", str(cfg), "--out", str(target), "--workers", "1"]) == 130
    assert "2 of 4 cases are finished and kept" in capsys.readouterr().err
    assert len(_rows(target / "results.csv")) == 2  # what finished is on disk
    assert json.loads((target / "manifest.json").read_text())["extra"]["status"] == "interrupted"
    monkeypatch.setattr(study, "run_case", real)
    capsys.readouterr()
    assert main(["study", str(cfg), "--out", str(target), "--workers", "1"]) == 0
    assert "2 already finished (skipped), 2 to run" in capsys.readouterr().err
    assert _without_time(_rows(target / "results.csv")) == _without_time(_rows(out / "results.csv"))


def test_case_ids_do_not_depend_on_the_order_of_the_grid(serial_run, tmp_path, capsys):
    import shutil

    cfg, out = serial_run
    reordered = _write(tmp_path, BASE + STUDY.replace("[60.0, 90.0]", "[90.0, 60.0]"))
    copy = tmp_path / "reordered"
    shutil.copytree(out, copy)
    capsys.readouterr()
    assert main(["study", str(reordered), "--out", str(copy), "--workers", "1"]) == 0
    assert "4 already finished (skipped), 0 to run" in capsys.readouterr().err
    ids = [r["case_id"] for r in _rows(copy / "results.csv")]
    old = [r["case_id"] for r in _rows(out / "results.csv")]
    assert ids == [old[2], old[3], old[0], old[1]]


def test_report_is_self_contained_with_embedded_pngs(serial_run):
    _, out = serial_run
    page = (out / "report.html").read_text(encoding="utf-8")
    images = re.findall(r'<img [^>]*src="([^"]+)"', page)
    assert len(images) >= 2
    for src in images:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert not re.search(r'(src|href)="(https?:)?//', page)  # nothing fetched from the network
    assert "<script" not in page
    assert "θ = 60°" not in page  # the legend is inside the image, the table in the page
    rows = _rows(out / "results.csv")
    failed = sum(r["status"] == "failed_blocks" for r in rows)
    others = sum(r["status"] not in ("ok", "failed_blocks") for r in rows)
    # outcomes (header + 6), failed-block and not-in-equilibrium cases (header + rows, when any),
    # combinations (header + 2), every case (header + 4)
    assert page.count("<tr>") == (1 + 6) + (1 + failed if failed else 0) \
        + (1 + others if others else 0) + (1 + 2) + (1 + 4)


def test_a_case_whose_solver_stops_on_an_overlap_is_a_failed_case(tmp_path, capsys):
    """With a rounding of 10 µm the overlap limit (5 µm) is far below the closures of the
    excavation, so the DEM stops with "overlap": the case must not pass as "ok" with the
    displacement of a stopped run — its outcome is overlap, with the solver's diagnostic, kept in
    results.csv without max_displacement_m, and the study exits 1; a re-run keeps it (the solver
    is deterministic) and still exits 1."""
    cfg = _write(tmp_path, BASE + """
[study]
[[study.cases]]
"solve.rounding_m" = 1e-5
""")
    out = tmp_path / "o"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 1
    assert "FAILED: solver stopped (overlap)" in capsys.readouterr().err
    (case_dir,) = (out / "cases").iterdir()
    record = json.loads((case_dir / "case.json").read_text())
    assert record["status"] == "overlap" and record["solve_status"] == "overlap"
    assert "overlap" in record["error"]
    rows = list(csv.DictReader(io.StringIO((out / "results.csv").read_text())))
    assert [r["status"] for r in rows] == ["overlap"] and rows[0]["max_displacement_m"] == ""
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 1
    err = capsys.readouterr().err
    assert "1 already finished (skipped), 0 to run" in err and "stopped by the solver" in err


def test_list_form_and_grid_combine(tmp_path, capsys):
    cfg = _write(tmp_path, BASE + """
[study]
[study.grid]
blocks.two_sets.theta_deg = [60.0, 90.0]
[[study.cases]]
"blocks.two_sets.alpha_deg" = 0.0
[[study.cases]]
blocks.two_sets.alpha_deg = 30.0
blocks.two_sets.spacing_m = [4.0, 4.0]
""")
    assert main(["study", str(cfg), "--out", str(tmp_path / "o"), "--list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 4
    assert "alpha_deg=0.0, theta_deg=60.0" in lines[0]
    assert "alpha_deg=30.0, spacing_m=[4.0, 4.0], theta_deg=90.0" in lines[3]
    assert not (tmp_path / "o").exists()  # --list writes nothing



LABELLED = """
[study]
[study.grid]
blocks.two_sets.theta_deg = [60.0, 90.0]
[[study.cases]]
label = "steep set"
"blocks.two_sets.alpha_deg" = 0.0
[[study.cases]]
blocks.two_sets.alpha_deg = 30.0
"""


def test_a_case_label_names_its_cases_and_changes_no_case_id(tmp_path, capsys):
    """``label`` in a [[study.cases]] table names its cases (with the grid's values) in --list,
    the progress lines and results.csv; it is not a config field, so the case ids are those of the
    same study without it. The cases of an unlabelled table keep their field values."""
    cfg = _write(tmp_path, BASE.split("[solve]")[0] + LABELLED)
    plain = _write(tmp_path, BASE.split("[solve]")[0] + LABELLED.replace('label = "steep set"\n', ""),
                   "plain.toml")
    assert main(["study", str(cfg), "--out", str(tmp_path / "o"), "--list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert main(["study", str(plain), "--out", str(tmp_path / "p"), "--list"]) == 0
    plain_lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[1] for line in lines] == [line.split()[1] for line in plain_lines]
    assert lines[0].endswith("steep set (theta_deg=60.0)") and lines[1].endswith("steep set (theta_deg=90.0)")
    assert lines[3].endswith("alpha_deg=30.0, theta_deg=90.0")
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 0
    assert "steep set (theta_deg=60.0) r=0" in capsys.readouterr().err  # the progress line
    rows = _rows(out / "results.csv")
    assert [r["label"] for r in rows] == ["steep set", "steep set", "", ""]
    assert list(rows[0])[:3] == ["case", "case_id", "label"]


@pytest.mark.parametrize("label", ['""', "42", '"a\\nb"', '"' + "x" * 61 + '"'])
def test_a_bad_case_label_exits_2_naming_it(tmp_path, capsys, label):
    cfg = _write(tmp_path, BASE + f"""
[study]
[[study.cases]]
label = {label}
"blocks.two_sets.alpha_deg" = 0.0
""")
    assert main(["study", str(cfg), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "study.cases" in err and "[0].label: must be a line of text of 1 to 60 characters" in err

@pytest.mark.parametrize("study, field, expected", [
    ('[study.grid]\nblocks.two_sets.thetaa_deg = [40.0]\n', "study.grid.blocks.two_sets.thetaa_deg",
     'unknown key .*did you mean "theta_deg"'),
    ('[study.grid]\nblocks.two_sets.theta_deg = [40.0, 95.0]\n', "study.grid.blocks.two_sets.theta_deg",
     r"must be <= 90.*study case 1"),
    ('[study.grid]\nblocks.two_sets.theta_deg = []\n', "study.grid", "empty list"),
    ('[study.grid]\nblocks.two_sets.theta_deg = 40.0\n', "study.grid", "must be a list"),
    ('[study.grid]\n"blocks.excavations[3].radius_m" = [1.0]\n',
     r"study.grid.blocks.excavations\[3\].radius_m", "index out of range"),
    ('[study.grid]\nblocks.seed = [1, 2]\n', "study.seed_fields", "also varied"),
    ('[study]\nrealizations = 0\n', "study.realizations", "must be >= 1"),
    ('[study]\nworkers = 2\n', "study.workers", "unknown key"),
])
def test_bad_study_exits_2_before_any_case_runs(tmp_path, capsys, study, field, expected):
    if not study.startswith("[study]"):
        study = "[study]\n" + study
    cfg = _write(tmp_path, BASE + "\n" + study)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(cfg) in err
    assert re.search(re.escape(field) if "\\" not in field else field, err), err
    assert re.search(expected, err), err
    assert not out.exists()


def test_solve_that_does_not_fit_the_model_exits_2_before_any_case_runs(tmp_path, capsys):
    cfg = _write(tmp_path, BASE.replace('excavate = ["tunnel"]', 'excavate = ["cavern"]') + STUDY)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out)]) == 2
    assert "cavern" in capsys.readouterr().err
    assert not out.exists()


def test_a_failing_case_is_recorded_and_the_others_finish(tmp_path, monkeypatch, capsys):
    import rockmass.study as study

    cfg = _write(tmp_path, BASE + STUDY)
    real = study._fractal

    def boom(document, path, model, traces=None):
        if document.blocks.two_sets.theta_deg == 90.0:
            raise RuntimeError("simulated failure")
        return real(document, path, model, traces)

    monkeypatch.setattr(study, "_fractal", boom)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 1
    rows = _rows(out / "results.csv")
    assert [r["status"] for r in rows][2:] == ["error", "error"]
    assert all(r["status"] != "error" for r in rows[:2])
    assert "simulated failure" in rows[2]["error"]
    assert "2 of 4 cases failed" in capsys.readouterr().err
    monkeypatch.setattr(study, "_fractal", real)  # a re-run retries only the failed cases
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 0
    assert "2 already finished (skipped), 2 to run" in capsys.readouterr().err
    assert all(r["status"] != "error" for r in _rows(out / "results.csv"))


def test_a_case_with_a_missing_input_file_fails_alone_and_the_manifest_is_written(
        tmp_path, monkeypatch, capsys):
    """A grid over blocks.traces with one file absent: that case fails with the file named, the
    others run, manifest.json records every input once (the absent one as missing) and the exit
    code is 1 (was 2: the manifest re-hashed the inputs and raised). Each distinct input is
    hashed once, not once per case and again for the manifest."""
    import hashlib

    import rockmass.manifest as manifest_module

    (tmp_path / "t.csv").write_text("x0,y0,x1,y1,set\n-5,-4,5,3,1\n-5,4,4,-5,1\n",
                                    encoding="utf-8")
    cfg = _write(tmp_path, BASE + """
[study]
realizations = 2
[study.grid]
"blocks.traces" = ["absent.csv", "t.csv"]
""")
    real = manifest_module.file_sha256
    hashed = []

    def counting(path):
        hashed.append(Path(path).name)
        return real(path)

    monkeypatch.setattr(manifest_module, "file_sha256", counting)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 1
    err = capsys.readouterr().err
    assert "2 of 4 cases failed" in err
    rows = _rows(out / "results.csv")
    assert [r["status"] for r in rows][:2] == ["error", "error"]
    assert all(r["status"] != "error" for r in rows[2:])
    for r in rows[:2]:
        assert "absent.csv: cannot read the blocks.traces file" in r["error"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["extra"]["failed"] == 2 and manifest["extra"]["finished"] == 2
    inputs = {Path(i["path"]).name: i for i in manifest["inputs"]}
    assert len(inputs) == len(manifest["inputs"]) == 3
    assert inputs["absent.csv"] == {"path": str(tmp_path / "absent.csv"), "sha256": None,
                                    "bytes": None, "missing": True}
    data = (tmp_path / "t.csv").read_bytes()
    assert inputs["t.csv"]["sha256"] == hashlib.sha256(data).hexdigest()
    assert inputs["t.csv"]["bytes"] == len(data)
    assert inputs["study.toml"]["sha256"] == hashlib.sha256(cfg.read_bytes()).hexdigest()
    assert sorted(hashed) == ["absent.csv", "study.toml", "t.csv"]


def test_joint_network_is_the_models_joints(tmp_path):
    """The box-counted segments are the joints the builder cut: same total length as the model's
    joint contacts (persistent sets, so every joint segment is a contact)."""
    from rockmass.blockgen import CONTACT_KINDS
    from rockmass.config import RockmassConfig
    from rockmass.study import _build_model, joint_network_segments
    import tomllib

    data = tomllib.loads(BASE)
    for seed in (0, 5):
        data["blocks"]["seed"] = seed
        doc = RockmassConfig.model_validate(data)
        model = _build_model(doc, tmp_path / "x.toml")
        segs = joint_network_segments(doc, tmp_path / "x.toml", model)
        length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]).sum()
        joint = model.contact_kind == CONTACT_KINDS.index("joint")
        # the builder snaps end points to its grid and collapses short edges (mm-scale moves)
        assert length == pytest.approx(model.contact_length_m[joint].sum(), rel=1e-4)


RANDOM_SETS = """[blocks]
[blocks.domain]
width_m = 10.0
height_m = 8.0
origin_xy_m = [2.0, -3.0]
[[blocks.sets]]
angle_deg = 25.0
spacing_m = 1.5
spacing_distribution = "lognormal"
spacing_std_m = 0.5
[[blocks.sets]]
angle_deg = 115.0
spacing_m = 2.0
spacing_distribution = "exponential"
"""


def test_box_counted_joints_are_where_the_built_model_has_its_joints(tmp_path):
    """The segments a study box-counts are the joints of the model blockgen built for the same
    config and seed. Expectation taken from the built model alone: the edges two blocks share
    along a joint contact (the blocks' polygons). Random spacings (lognormal, exponential) make
    every joint's position depend on the seed, so segments drawn by any other seeding rule miss
    those edges by about a spacing; the last check shows the test sees that (another seed)."""
    import shapely
    import tomllib

    from rockmass.blockgen import CONTACT_KINDS
    from rockmass.config import RockmassConfig
    from rockmass.study import _build_model, joint_network_segments

    data = tomllib.loads(RANDOM_SETS)
    path = tmp_path / "x.toml"
    for seed in (0, 12345):  # fixed seeds: no sliver is merged, so every joint stays a contact
        doc = RockmassConfig.model_validate({"blocks": {**data["blocks"], "seed": seed}})
        model = _build_model(doc, path)
        polygons = model.to_shapely()
        joint = np.flatnonzero(model.contact_kind == CONTACT_KINDS.index("joint"))
        shared = [shapely.intersection(polygons[a].boundary, polygons[b].boundary)
                  for a, b in model.contact_blocks[joint]]
        corners = shapely.points(shapely.get_coordinates(np.array(shared)))

        def miss_m(study_seed):
            other = RockmassConfig.model_validate({"blocks": {**data["blocks"], "seed": study_seed}})
            segs = joint_network_segments(other, path, model)
            network = shapely.multilinestrings(segs.reshape(-1, 2, 2))
            return float(shapely.distance(corners, network).max()), segs

        miss, segs = miss_m(seed)
        assert miss < 1e-6  # the builder snaps to a 1e-11 m grid
        length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]).sum()
        assert length == pytest.approx(model.contact_length_m[joint].sum(), rel=1e-9)
        assert miss_m(seed + 1)[0] > 0.1  # spacings of 1.5 m and 2 m: a wrong rule is seen


def test_realization_seeds_follow_the_seed_sequence_rule():
    """Pinned values: a resumed study recognises its finished cases by case ids that include the
    seeds, and common random numbers need realization r to get the same seed in every run and
    every rockmass version, so the rule must never drift. The literals were computed once with
    numpy alone, per the docstring's rule (63 bits of the child with spawn key (r,) of
    SeedSequence(root)), as SeedSequence(root).spawn(r + 1)[r].generate_state(2, np.uint32)."""
    from rockmass.study_config import realization_seed

    seeds = [realization_seed(3, r) for r in range(5)]
    assert len(set(seeds)) == 5 and all(0 <= s < 2 ** 63 for s in seeds)
    assert realization_seed(3, 2) == 7412683631247761940
    assert realization_seed(7, 0) == 2579397289629868333  # the seeds of STUDY (seed = 7)
    assert realization_seed(7, 1) == 7771707183050906158
    assert realization_seed(2 ** 63 - 1, 9999) == 7870244885312304718


def test_dask_local_cluster_gives_the_same_results(serial_run, tmp_path, capsys):
    distributed = pytest.importorskip("dask.distributed")
    cfg, out = serial_run
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        target = tmp_path / "dask"
        code = main(["study", str(cfg), "--out", str(target), "--scheduler",
                     cluster.scheduler_address])
        assert code == 0, capsys.readouterr().err
    assert _without_time(_rows(target / "results.csv")) == _without_time(_rows(out / "results.csv"))
    assert json.loads((target / "manifest.json").read_text())["extra"]["executor"].startswith("dask")
    _assert_one_thread_and_warmed_once(target, n_workers=2)


def _assert_one_thread_and_warmed_once(target, n_workers):
    """Every case ran with one numba thread in a worker process whose kernels were warmed exactly
    once, before its first case (the pool's initializer / the Dask worker plugin)."""
    records = [json.loads(p.read_text()) for p in (target / "cases").glob("*/case.json")]
    assert len(records) == 4
    assert {r["numba_threads"] for r in records} == {1}
    assert {r["worker_warmups"] for r in records} == {1}
    pids = {r["worker_pid"] for r in records}
    assert 1 <= len(pids) <= n_workers  # a slow starter may get none
    assert os.getpid() not in pids  # the cases ran in the workers, not in the study's process


def test_unreachable_scheduler_exits_2_before_any_case_runs(tmp_path, capsys):
    pytest.importorskip("dask.distributed")
    cfg = _write(tmp_path, BASE + STUDY)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out), "--scheduler", "tcp://127.0.0.1:9",
                 "--connect-timeout", "2"]) == 2
    assert "cannot reach the Dask scheduler" in capsys.readouterr().err
    assert not out.exists()


def test_scheduler_without_dask_exits_2(tmp_path, capsys, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name.startswith("dask"):
            raise ImportError("No module named 'dask'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    cfg = _write(tmp_path, BASE + STUDY)
    assert main(["study", str(cfg), "--out", str(tmp_path / "o"), "--scheduler", "tcp://x:1"]) == 2
    assert "rockmass[dask]" in capsys.readouterr().err


def test_study_without_solve_reports_blocks_and_d_box_only(tmp_path):
    cfg = _write(tmp_path, BASE.split("[solve]")[0] + STUDY)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 0
    rows = _rows(out / "results.csv")
    assert len(rows) == 4 and all(r["d_box"] and r["max_displacement_m"] == "" for r in rows)
    assert "D_box versus P21" in (out / "report.html").read_text(encoding="utf-8")


def test_cavern_sample_is_the_seed_000_study(capsys, tmp_path):
    """samples/study_cavern.toml: theta 40/60/90 deg x 3 spacings x 2 realizations (validated only;
    running it takes a few minutes)."""
    assert main(["study", str(SAMPLES / "study_cavern.toml"), "--out", str(tmp_path / "o"),
                 "--list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 18
    assert {re.search(r"theta_deg=(\d+)", line).group(1) for line in lines} == {"40", "60", "90"}


def test_case_config_toml_reruns_the_case_alone_with_the_same_numbers(serial_run, tmp_path):
    """cases/<id>/config.toml is the case as a config of its own: rockmass solve on it gives the
    study's maximum displacement (boundary blocks in equilibrium) to the last bit (the same code
    path, one numba thread or not)."""
    import tomllib

    _, out = serial_run
    row = _rows(out / "results.csv")[3]
    case_cfg = out / "cases" / row["case_id"] / "config.toml"
    data = tomllib.loads(case_cfg.read_text(encoding="utf-8"))
    assert "study" not in data and data["blocks"]["seed"] == int(row["seed"])
    assert main(["solve", str(case_cfg), "--out", str(tmp_path / "solo")]) == 0
    result = json.loads((tmp_path / "solo" / "result.json").read_text())
    assert result["stages"][-1]["max_displacement_boundary_equilibrium_m"] \
        == float(row["max_displacement_boundary_m"])
    assert int(row["steps"]) == sum(s["steps"] for s in result["stages"])


@pytest.mark.skipif(_chromium.chromium() is None, reason=_chromium.SKIP_REASON)
def test_report_renders_in_headless_chromium_with_every_image_loaded(serial_run, tmp_path):
    """Open report.html in headless Chromium (no network): every <img> decodes; a screenshot is
    kept as an artifact (in $ROCKMASS_TEST_ARTIFACTS when set)."""
    _, out = serial_run
    loaded, total = _chromium.count_loaded_images(out / "report.html", tmp_path)
    assert total >= 3 and loaded == total
    shot = _chromium.screenshot(out / "report.html", tmp_path / "study_report.png")
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_dfn_section_study_varies_p32_and_reseeds_the_dfn(tmp_path):
    """Seed 001 kind of study: DFN sets cut by a plane, P32 of one set varied, realizations reseed
    [dfn] (and [blocks]); P32 is in results.csv and denser networks give a larger D_box."""
    text = (SAMPLES / "blocks_dfn_section.toml").read_text(encoding="utf-8") + """
[study]
realizations = 2
[study.grid]
"dfn.sets[0].intensity.value" = [0.3333333333333333, 1.0]
"""
    cfg = _write(tmp_path, text)
    out = tmp_path / "out"
    assert main(["study", str(cfg), "--out", str(out), "--workers", "1"]) == 0
    rows = _rows(out / "results.csv")
    assert [float(r["p32"]) for r in rows] == pytest.approx([1.0, 1.0, 1 + 2 / 3, 1 + 2 / 3])
    assert rows[0]["d_box"] != rows[1]["d_box"]  # realizations differ: the DFN was reseeded
    case = json.loads((out / "cases" / rows[1]["case_id"] / "case.json").read_text())
    assert case["config"]["dfn"]["seed"] == case["config"]["blocks"]["seed"] == int(rows[1]["seed"])
    low = np.mean([float(r["d_box"]) for r in rows[:2]])
    high = np.mean([float(r["d_box"]) for r in rows[2:]])
    assert high > low and all(r["max_displacement_m"] == "" for r in rows)
