"""``rockmass study`` outcomes (issue 14 item 6): a case is ok, failed_blocks, not_converged,
unstable, overlap or error; displacements are over the blocks in equilibrium; the report's
statistics and main series use the ok cases only; resume keeps every outcome but error.

The DEM is replaced by fake :class:`rockmass.solver.result.Result` objects (blocks and box counting
still run for real), so each case's outcome and numbers are set by the test and every expected
value below is computed from them here, independently of the study code. The real solver runs in
test_study.py.
"""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from rockmass.cli import main

from .test_study import BASE

# 3 realizations of two parameter combinations (the excavation stage's step cap is the varied
# field: it changes nothing the fake solver does, and it names the combination)
STUDY = """
[study]
realizations = 3
seed = 11
[study.grid]
"solve.stages[1].max_steps" = [250, 260]
"""

FALL_M = 13.6  # a keyblock falling under gravity at the step cap (issue 14: 0.4-13.6 m)


def _stage(name, *, status="converged", kind="static", converged=True, steps=120,
           equilibrium_m=0.0, boundary_equilibrium_m=0.0, any_block_m=None, failed=(),
           monitors=None, worst_ratio=1e-6, worst_block=4, diagnostic=None, broken=0):
    """A StageResult as the solver returns it. ``any_block_m``: the displacement over every block, falls included
    (default: the equilibrium one)."""
    from rockmass.solver.result import StageResult

    any_block_m = equilibrium_m if any_block_m is None else any_block_m
    values = dict(
        name=name, kind=kind, status=status, steps=steps, time_step_s=1e-4,
        stable_time_step_s=2e-4, simulated_time_s=steps * 1e-4, converged=converged,
        unbalanced_ratio=worst_ratio / 10, max_displacement_m=any_block_m,
        max_displacement_boundary_m=any_block_m, max_displacement_stage_m=any_block_m,
        slipping_contacts=0, open_contacts=0, newly_broken_contacts=0, broken_contacts=broken,
        detached_blocks=0, blocks_removed=len(failed), energy={}, wall_time_s=0.01,
        contact_rebuilds=0, diagnostic=diagnostic,
        # the fields issue 14 adds
        max_displacement_equilibrium_m=equilibrium_m,
        max_displacement_boundary_equilibrium_m=boundary_equilibrium_m,
        monitors=dict(monitors or {}), worst_block=worst_block, worst_ratio=worst_ratio,
        failed_blocks=[dict(f) for f in failed])
    return StageResult(**values)


def _result(stages, status="ok", diagnostic=None):
    from rockmass.solver.result import Result

    zeros = np.zeros((1, 2))
    return Result(stages=list(stages), displacement_m=zeros, rotation_rad=np.zeros(1),
                  velocity_m_s=zeros, active=np.ones(1, bool), history={}, frames=[],
                  block_energy={}, status=status, diagnostic=diagnostic)


def _monitors(scale):
    return {"crown": 1.0 * scale, "left_wall": 0.5 * scale, "right_wall": 0.4 * scale,
            "invert": 0.2 * scale}


def _ok(boundary_m, overall_m=None):
    overall_m = boundary_m * 1.5 if overall_m is None else overall_m
    return _result([_stage("equilibrium", worst_ratio=2e-6),
                    _stage("tunnel", equilibrium_m=overall_m, boundary_equilibrium_m=boundary_m,
                           monitors=_monitors(boundary_m), worst_ratio=5e-6)])


FALL = {"block": 17, "area_m2": 1.25, "mechanism": "fall", "displacement_m": FALL_M,
        "x_m": 0.3, "y_m": 2.1}
SLIDE = {"block": 9, "area_m2": 0.5, "mechanism": "slide", "displacement_m": 0.41,
         "x_m": -1.9, "y_m": 0.4}


def _failed_blocks(boundary_m, overall_m):
    """A keyblock falls in the excavation stage, a wall block slides: both are taken out and the
    rest reaches equilibrium; the displacement over every block is the fall's."""
    return _result([_stage("equilibrium", worst_ratio=3e-6, failed=[SLIDE], status="failed_blocks",
                           any_block_m=0.41),
                    _stage("tunnel", status="failed_blocks", equilibrium_m=overall_m,
                           boundary_equilibrium_m=boundary_m, any_block_m=FALL_M,
                           monitors=_monitors(boundary_m), failed=[FALL], worst_ratio=8e-6)],
                   status="failed_blocks")


def _not_converged():
    return _result([_stage("equilibrium"),
                    _stage("tunnel", status="max_steps", converged=False, steps=260,
                           equilibrium_m=0.9, boundary_equilibrium_m=0.9, worst_ratio=0.3,
                           worst_block=23, monitors=_monitors(0.9),
                           # the runner's words for a stage that ran out of steps
                           diagnostic="no equilibrium within max_steps = 260 steps: model "
                                      "ratio 0.03 (tolerance 1e-05), worst block 23 at 0.3 "
                                      "(block tolerance 0.001)")])


# (max_steps of the tunnel stage, realization) -> what the fake solver returns
OUTCOMES = {
    (250, 0): _ok(2.0e-3), (250, 1): _ok(4.0e-3), (250, 2): _failed_blocks(6.0e-3, 6.5e-3),
    (260, 0): _ok(5.0e-3), (260, 1): _not_converged(), (260, 2): _ok(7.5e-3),
}


class _Calls(list):
    """The cases solved, in order, and ``raising``: the cases made to crash."""

    raising: set


@pytest.fixture
def fake_solver(monkeypatch):
    """Replace the DEM by OUTCOMES (the case is known from the task run_case is given); returns
    the list of (max_steps, realization) solved, in order. ``fake_solver.raising`` (a set of keys)
    makes those cases raise."""
    import rockmass.solve_stage as solve_stage
    import rockmass.study as study

    real_run_case = study.run_case
    current = {}
    calls = _Calls()

    def tracking(task):
        current["task"] = task
        return real_run_case(task)

    def fake_solve(model, settings, config_path, progress=None):
        task = current["task"]
        key = (int(task["params"]["solve.stages[1].max_steps"]), int(task["realization"]))
        calls.append(key)
        if key in calls.raising:
            raise RuntimeError("simulated solver crash")
        return OUTCOMES[key]

    calls.raising = set()
    monkeypatch.setattr(study, "run_case", tracking)
    monkeypatch.setattr(solve_stage, "solve", fake_solve)
    return calls


@pytest.fixture
def study_file(tmp_path):
    path = tmp_path / "study.toml"
    path.write_text(BASE + STUDY, encoding="utf-8")
    return path


def _rows(path: Path) -> list[dict]:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def _key(row):
    return int(row["solve.stages[1].max_steps"]), int(row["realization"])


def _run(study_file, out, *extra):
    return main(["study", str(study_file), "--out", str(out), "--workers", "1", *extra])


# ------------------------------------------------------------------------------ pure functions


@pytest.mark.parametrize("result, expected", [
    (_ok(1e-3), "ok"),
    (_failed_blocks(1e-3, 2e-3), "failed_blocks"),
    (_not_converged(), "not_converged"),
    # blocks failed and then the rest did not settle: the model is not in equilibrium
    (_result([_stage("tunnel", status="failed_blocks", converged=False, failed=[FALL],
                     diagnostic="1 block(s) kept moving and were taken out: 7 (fall, 0.5 m²); "
                                "the rest did not reach equilibrium within max_steps")],
             status="failed_blocks"), "not_converged"),
    # the run was stopped: whatever the stages say
    (_result([_stage("tunnel", status="overlap", converged=False)], status="overlap",
             diagnostic="blocks 3 and 4 overlap by 2 mm"), "overlap"),
    (_result([_stage("tunnel", status="unstable", converged=False)], status="unstable",
             diagnostic="energy residual 3.1 x the work in"), "unstable"),
    # a dynamic stage has no equilibrium to reach (converged None)
    (_result([_stage("equilibrium"), _stage("shake", kind="dynamic", status="completed",
                                            converged=None)]), "ok"),
])
def test_case_outcome_follows_the_precedence_stopped_unconverged_failed_ok(result, expected):
    from rockmass.study import case_outcome

    status, reason = case_outcome(result)
    assert status == expected
    if expected in ("ok", "failed_blocks"):
        assert reason is None
    elif expected == "not_converged":
        assert "'tunnel'" in reason and "max_steps" in reason
    else:
        assert result.diagnostic in reason


def test_case_outcome_rejects_an_unknown_solver_status():
    from rockmass.study import case_outcome

    with pytest.raises(ValueError, match="unknown solver status 'melted'"):
        case_outcome(_result([_stage("tunnel")], status="melted"))


def test_outcome_summary_counts_cases_and_failed_blocks_by_mechanism():
    from rockmass.study import outcome_counts, outcome_summary

    records = [{"status": "ok"}] * 5 + [
        {"status": "failed_blocks", "failed_mechanism_counts": {"fall": 2, "slide": 1}},
        {"status": "failed_blocks", "failed_mechanism_counts": {"fall": 1}},
        {"status": "not_converged"}, {"status": "error"}]
    assert outcome_counts(records) == {"ok": 5, "failed_blocks": 2, "not_converged": 1,
                                       "unstable": 0, "overlap": 0, "error": 1}
    assert outcome_summary(records, 10) == ("5 of 10 cases in equilibrium; 2 with failed blocks "
                                            "(4 blocks: fall 3, slide 1); 1 not converged; "
                                            "1 error; 1 not run")


# ------------------------------------------------------------------------------ results.csv


def test_failed_blocks_case_reports_the_equilibrium_displacement_not_the_fall(
        study_file, tmp_path, fake_solver, capsys):
    """The case whose keyblock falls 13.6 m: status failed_blocks, max_displacement_m is the
    boundary blocks left in equilibrium (6 mm), the failed blocks are counted apart over both
    stages (2 blocks, 1.75 m², fall:1 slide:1), monitors from the last stage; the study exits 0."""
    out = tmp_path / "out"
    assert _run(study_file, out) == 0
    rows = {_key(r): r for r in _rows(out / "results.csv")}
    assert sorted(rows) == sorted(OUTCOMES)
    row = rows[(250, 2)]
    assert row["status"] == "failed_blocks" and row["error"] == ""
    assert float(row["max_displacement_m"]) == float(row["max_displacement_boundary_m"]) == 6.0e-3
    assert float(row["max_displacement_overall_m"]) == 6.5e-3
    for column in ("max_displacement_m", "max_displacement_boundary_m",
                   "max_displacement_overall_m"):
        assert float(row[column]) < 0.1  # never the fall
    assert int(row["failed_blocks"]) == 2
    assert float(row["failed_area_m2"]) == FALL["area_m2"] + SLIDE["area_m2"]
    assert row["failed_mechanisms"] == "fall:1 slide:1"
    assert float(row["worst_ratio"]) == 8e-6  # the largest over the static stages
    assert float(row["crown_displacement_m"]) == 6.0e-3
    assert float(row["left_wall_displacement_m"]) == 0.5 * 6.0e-3
    assert float(row["right_wall_displacement_m"]) == 0.4 * 6.0e-3
    assert float(row["invert_displacement_m"]) == 0.2 * 6.0e-3
    assert row["converged"] == "true" and row["solve_status"] == "failed_blocks"
    record = json.loads((out / "cases" / row["case_id"] / "case.json").read_text())
    assert [(b["stage"], b["block"], b["mechanism"], b["displacement_m"])
            for b in record["failed_block_list"]] == [("equilibrium", 9, "slide", 0.41),
                                                      ("tunnel", 17, "fall", FALL_M)]
    ok = rows[(250, 0)]
    assert ok["status"] == "ok" and float(ok["max_displacement_m"]) == 2.0e-3
    assert ok["failed_blocks"] == "0" and ok["failed_mechanisms"] == ""
    assert float(ok["failed_area_m2"]) == 0.0


def test_not_converged_case_has_no_max_displacement_and_says_which_stage(
        study_file, tmp_path, fake_solver):
    out = tmp_path / "out"
    assert _run(study_file, out) == 0  # a stage that does not converge is a result, not a failure
    row = {_key(r): r for r in _rows(out / "results.csv")}[(260, 1)]
    assert row["status"] == "not_converged" and row["max_displacement_m"] == ""
    assert float(row["max_displacement_boundary_m"]) == 0.9  # the solver's value, kept apart
    assert "stage 'tunnel'" in row["error"] and "worst block 23" in row["error"]
    assert float(row["worst_ratio"]) == 0.3 and row["converged"] == "false"


def test_cli_summary_and_json_count_the_outcomes(study_file, tmp_path, fake_solver, capsys):
    line = ("4 of 6 cases in equilibrium; 1 with failed blocks (2 blocks: fall 1, slide 1); "
            "1 not converged")
    assert _run(study_file, tmp_path / "a") == 0
    assert line in capsys.readouterr().out
    assert _run(study_file, tmp_path / "b", "--json") == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["outcomes"] == {"ok": 4, "failed_blocks": 1, "not_converged": 1,
                                   "unstable": 0, "overlap": 0, "error": 0}
    assert summary["outcome_summary"] == line
    manifest = json.loads((tmp_path / "b" / "manifest.json").read_text())
    assert manifest["extra"]["outcomes"] == summary["outcomes"]
    assert manifest["extra"]["finished"] == 6 and manifest["extra"]["failed"] == 0


# ------------------------------------------------------------------------------ the report


def test_report_statistics_and_main_series_use_ok_cases_only(study_file, tmp_path, fake_solver,
                                                             monkeypatch):
    """Per combination: mean ± sd over its ok cases (computed here with numpy from the fake
    displacements and the D_box of results.csv), the failed-block case as a cross at its
    equilibrium displacement, the unconverged case listed with its reason, never averaged."""
    import matplotlib.axes

    drawn = {"errorbar": [], "x": []}
    real_errorbar, real_scatter = matplotlib.axes.Axes.errorbar, matplotlib.axes.Axes.scatter

    def errorbar(self, x, y, *args, **kwargs):
        if kwargs.get("fmt") == "o":  # the mean markers of the D_box-displacement plot
            drawn["errorbar"].append((float(x), float(y)))
        return real_errorbar(self, x, y, *args, **kwargs)

    def scatter(self, x, y, *args, **kwargs):
        if kwargs.get("marker") == "x" and len(x):
            drawn["x"].extend(zip(map(float, x), map(float, y)))
        return real_scatter(self, x, y, *args, **kwargs)

    monkeypatch.setattr(matplotlib.axes.Axes, "errorbar", errorbar)
    monkeypatch.setattr(matplotlib.axes.Axes, "scatter", scatter)
    out = tmp_path / "out"
    assert _run(study_file, out) == 0
    rows = {_key(r): r for r in _rows(out / "results.csv")}
    disp_mm = {(250, 0): 2.0, (250, 1): 4.0, (260, 0): 5.0, (260, 2): 7.5}  # the ok cases
    expected = {}
    for steps in (250, 260):
        keys = [k for k in disp_mm if k[0] == steps]
        d = np.array([float(rows[k]["d_box"]) for k in keys])
        y = np.array([disp_mm[k] for k in keys])
        expected[steps] = (d.mean(), d.std(ddof=1), y.mean(), y.std(ddof=1), len(keys))

    # the report's data
    import rockmass.study_report as report
    from rockmass.study import load_finished
    from rockmass.study_config import expand_cases, load_study

    document, raw = load_study(study_file)
    cases = expand_cases(document, raw, study_file)
    data = report.report_data(document.study, cases, load_finished(out, cases))
    assert [g["n"] for g in data["groups"]] == [3, 3]
    for g, steps in zip(data["groups"], (250, 260)):
        dm, dsd, ym, ysd, n = expected[steps]
        assert g["n_ok"] == g["displacement_m"]["n"] == g["d_box"]["n"] == n == 2
        assert g["displacement_m"]["mean"] * 1e3 == pytest.approx(ym, rel=1e-12)
        assert g["displacement_m"]["sd"] * 1e3 == pytest.approx(ysd, rel=1e-12)
        assert g["d_box"]["mean"] == pytest.approx(dm, rel=1e-12)
        assert g["d_box"]["sd"] == pytest.approx(dsd, rel=1e-12)
    assert data["groups"][0]["outcomes"]["failed_blocks"] == 1
    assert data["groups"][1]["outcomes"]["not_converged"] == 1
    (failed,) = data["failed_block_cases"]
    assert (failed["realization"], failed["displacement_m"], failed["failed_mechanisms"]) \
        == (2, 6.0e-3, "fall:1 slide:1")
    (stuck,) = data["not_in_equilibrium"]
    assert stuck["status"] == "not_converged" and "stage 'tunnel'" in stuck["reason"]

    # the plot: one mean marker per combination, from the ok cases; the failed case as a cross
    means = sorted((expected[s][0], expected[s][2]) for s in (250, 260))
    assert np.ravel(sorted(drawn["errorbar"])) == pytest.approx(np.ravel(means), rel=1e-12)
    assert drawn["x"][0] == pytest.approx((float(rows[(250, 2)]["d_box"]), 6.0), rel=1e-12)
    assert all(y < 100 for _, y in drawn["x"])  # no fall (13.6 m) anywhere

    # the page
    page = (out / "report.html").read_text(encoding="utf-8")
    assert ("4 of 6 cases in equilibrium; 1 with failed blocks (2 blocks: fall 1, slide 1); "
            "1 not converged") in page
    for steps in (250, 260):
        _, _, ym, ysd, _ = expected[steps]
        assert f"<td>{ym:.4g} ± {ysd:.2g}</td>" in page  # mm, in the combinations table
    # what averaging the failed case in would give: its equilibrium blocks, or its fall
    for mixed in (np.mean([2.0, 4.0, 6.0]), np.mean([2.0, 4.0, FALL_M * 1e3])):
        assert f"<td>{mixed:.4g} ± " not in page
    assert 'id="failed-blocks"' in page and 'id="not-in-equilibrium"' in page
    assert "blocks failed" in page and "fall:1 slide:1" in page


# ------------------------------------------------------------------------------ resume


def test_resume_keeps_every_outcome_but_error(study_file, tmp_path, fake_solver, capsys):
    """A first run where one case crashes (error, exit 1); the re-run solves only that case: the
    failed_blocks and not_converged cases are kept as they are (the solver is deterministic), and
    a record written by an older rockmass (no record_version: its displacement may be a fall) is
    run again."""
    out = tmp_path / "out"
    fake_solver.raising.add((260, 0))
    assert _run(study_file, out) == 1
    err = capsys.readouterr().err
    assert "1 of 6 cases failed" in err and "simulated solver crash" in err
    rows = {_key(r): r for r in _rows(out / "results.csv")}
    assert rows[(260, 0)]["status"] == "error"
    assert "RuntimeError: simulated solver crash" in rows[(260, 0)]["error"]
    assert rows[(260, 0)]["max_displacement_m"] == ""
    kept = {k: (out / "cases" / rows[k]["case_id"] / "case.json").read_bytes()
            for k in [(250, 2), (260, 1)]}
    old = out / "cases" / rows[(250, 0)]["case_id"] / "case.json"
    record = json.loads(old.read_text())
    del record["record_version"]
    old.write_text(json.dumps(record))

    fake_solver.raising.clear()
    fake_solver.clear()
    assert _run(study_file, out) == 0
    assert "4 already finished (skipped), 2 to run" in capsys.readouterr().err
    assert sorted(fake_solver) == [(250, 0), (260, 0)]
    for k, content in kept.items():
        assert (out / "cases" / rows[k]["case_id"] / "case.json").read_bytes() == content
    statuses = {_key(r): r["status"] for r in _rows(out / "results.csv")}
    assert statuses == {(250, 0): "ok", (250, 1): "ok", (250, 2): "failed_blocks",
                        (260, 0): "ok", (260, 1): "not_converged", (260, 2): "ok"}


def test_overlap_case_is_kept_on_resume_and_the_study_exits_1(study_file, tmp_path, monkeypatch,
                                                              capsys):
    import rockmass.solve_stage as solve_stage

    calls = []

    def overlap(model, settings, config_path, progress=None):
        calls.append(1)
        return _result([_stage("equilibrium"),
                        _stage("tunnel", status="overlap", converged=False, equilibrium_m=0.2)],
                       status="overlap", diagnostic="blocks 3 and 8 overlap by 4 mm")

    monkeypatch.setattr(solve_stage, "solve", overlap)
    cfg = tmp_path / "one.toml"
    cfg.write_text(BASE + "\n[study]\n", encoding="utf-8")
    out = tmp_path / "out"
    assert _run(cfg, out) == 1
    (row,) = _rows(out / "results.csv")
    assert row["status"] == "overlap" and row["max_displacement_m"] == ""
    assert "blocks 3 and 8 overlap by 4 mm" in row["error"]
    assert "stopped by the solver (1 overlap" in capsys.readouterr().err
    assert _run(cfg, out) == 1
    assert "1 already finished (skipped), 0 to run" in capsys.readouterr().err
    assert len(calls) == 1


def test_new_cracks_are_the_bonds_broken_after_the_initial_equilibrium(study_file, tmp_path,
                                                                       fake_solver, monkeypatch):
    """Three bonds broke settling under gravity, seven by the end: broken_contacts 7, of which
    the excavation made new_cracks = 4."""
    cracked = _result([_stage("equilibrium", broken=3),
                       _stage("tunnel", equilibrium_m=1e-3, boundary_equilibrium_m=1e-3,
                              monitors=_monitors(1e-3), broken=7)])
    monkeypatch.setitem(OUTCOMES, (250, 0), cracked)
    assert _run(study_file, tmp_path / "o") in (0, 1)
    row = next(r for r in _rows(tmp_path / "o" / "results.csv") if _key(r) == (250, 0))
    assert (int(row["broken_contacts"]), int(row["new_cracks"])) == (7, 4)
