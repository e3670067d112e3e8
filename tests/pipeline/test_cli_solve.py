"""``rockmass solve CONFIG --out DIR`` and the ``[solve]`` config section."""

from __future__ import annotations

import csv
import json
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

# 4 x 2 square blocks of 0.25 m, gravity, base fixed, a static stage and a short shaking
TINY = """[blocks]
[blocks.domain]
width_m = 1.0
height_m = 0.5
[[blocks.sets]]
name = "h"
angle_deg = 0.0
spacing_m = 0.25
origin_xy_m = [0.0, 0.0]
[[blocks.sets]]
name = "v"
angle_deg = 90.0
spacing_m = 0.25
origin_xy_m = [0.0, 0.0]

[solve]
[solve.material]
density_kg_m3 = 2700.0
[solve.joints.default]
model = "coulomb"
kn_pa_m = {kn}
ks_pa_m = {ks}
friction_deg = 30.0
[solve.joints.v]
model = "cy"
an_pa_m = 1e9
as_pa_m = 5e8
[[solve.fixes]]
where = "bottom"
[[solve.velocity_inputs]]
where = "bottom"
component = "x"
history = {{ type = "sine", amplitude = 0.05, frequency_hz = 20.0, cycles = 2 }}
[[solve.monitors]]
name = "top"
point_xy_m = [0.6, 0.4]
[[solve.monitors]]
name = "base"
block = 0
[[solve.stages]]
name = "gravity"
max_steps = 3000
[[solve.stages]]
name = "shake"
kind = "dynamic"
duration_s = 0.12
frames = 4
"""


def _write(tmp_path, text, name="c.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _tiny(tmp_path, kn="1e9", ks="5e8", extra="", name="c.toml"):
    return _write(tmp_path, TINY.format(kn=kn, ks=ks) + extra, name)


def _no_nan(text):
    def refuse(token):
        raise AssertionError(f"{token} in JSON")
    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("solve")
    path = _tiny(tmp)
    out = tmp / "out"
    code = main(["solve", str(path), "--out", str(out)])
    return path, out, code


def test_tiny_model_end_to_end_writes_every_output(tiny_run):
    _, out, code = tiny_run
    assert code == 0
    names = {p.name for p in out.iterdir()}
    assert {"result.json", "history.csv", "blocks.pvd", "block_energy.csv", "contacts.csv",
            "blocks.json", "manifest.json"} <= names
    vtus = sorted(n for n in names if re.fullmatch(r"blocks_\d{4}\.vtu", n))
    result = _no_nan((out / "result.json").read_text())
    assert result["status"] == "ok" and result["diagnostic"] is None
    assert [s["name"] for s in result["stages"]] == ["gravity", "shake"]
    assert result["stages"][0]["converged"] is True
    assert result["stages"][1]["status"] == "completed"
    assert result["stages"][1]["simulated_time_s"] == pytest.approx(0.12, rel=0.02)
    assert len(vtus) == len(result["frames"]) >= 4
    assert [f["file"] for f in result["frames"]] == vtus
    assert set(result["timings_s"]) >= {"load_s", "blocks_s", "solve_s"}
    assert "block_energy_vs_volume" in result
    assert not list(out.glob(".tmp-*"))


def test_pvd_lists_every_vtu_with_increasing_times(tiny_run):
    _, out, _ = tiny_run
    root = ET.parse(out / "blocks.pvd").getroot()
    sets = root.find("Collection").findall("DataSet")
    files = [d.get("file") for d in sets]
    assert files == sorted(p.name for p in out.glob("blocks_*.vtu"))
    times = [float(d.get("timestep")) for d in sets]
    assert all(b > a for a, b in zip(times, times[1:]))


def test_vtu_frames_are_readable_and_hold_the_rigid_motion(tiny_run):
    meshio = pytest.importorskip("meshio")
    from rockmass.blockgen import read_json

    _, out, _ = tiny_run
    model = read_json(out / "blocks.json")
    result = json.loads((out / "result.json").read_text())
    last = meshio.read(out / result["frames"][-1]["file"])
    assert {"displacement", "velocity", "block_id", "region", "active",
            "rotation_rad"} <= set(last.cell_data)
    ids = np.concatenate(last.cell_data["block_id"])
    assert sorted(ids.tolist()) == list(range(model.n_blocks))
    disp = np.concatenate(last.cell_data["displacement"])
    rot = np.concatenate(last.cell_data["rotation_rad"])
    assert np.isfinite(disp).all() and disp.shape == (model.n_blocks, 3)
    # every polygon is the block moved rigidly: its centroid = original centroid + displacement
    conn = np.concatenate([c.data for c in last.cells], axis=0) if len({c.data.shape[1] for c in last.cells}) == 1 else None
    if conn is not None:
        cen = last.points[conn][:, :, :2].mean(axis=1)
        squares = np.isclose(model.area_m2[ids], 0.0625)
        expect = model.centroid_xy_m[ids] + disp[:, :2]
        assert np.allclose(cen[squares], expect[squares], atol=1e-9)
    assert np.isfinite(rot).all()


def test_history_csv_has_the_monitor_columns(tiny_run):
    _, out, _ = tiny_run
    with open(out / "history.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    cols = set(rows[0])
    assert {"time_s", "stage", "unbalanced_ratio", "kinetic_energy_j", "top_ux_m", "top_uy_m",
            "top_vx_m_s", "base_ux_m", "top_contact_fy_n"} <= cols
    assert {r["stage"] for r in rows} == {"gravity", "shake"}
    assert all(math.isfinite(float(r["top_ux_m"])) for r in rows)
    with open(out / "block_energy.csv", newline="") as fh:
        energy = list(csv.DictReader(fh))
    assert list(energy[0]) == ["block_id", "region", "volume_m3", "mass_kg", "peak_velocity_m_s",
                               "peak_kinetic_energy_j"]
    assert float(energy[0]["mass_kg"]) == pytest.approx(2700 * 0.0625)


def test_sine_input_starts_with_the_dynamic_stage(tiny_run):
    """Two whole cycles: the base block is back where it started (the history's clock starts with
    the shaking, not with the static pseudo-time before it)."""
    _, out, _ = tiny_run
    result = json.loads((out / "result.json").read_text())
    base = result["monitors"]["base"]
    assert base["block"] == 0
    assert base["contacts_at_end"] >= 1 and base["max_contact_plastic_slip_m"] >= 0.0
    shake = base["stages"][-1]
    assert abs(shake["ux_m"]) < 1e-6
    # peak table displacement 2 A / (2 pi f) = 0.8 mm was reached during the stage
    assert shake["max_displacement_in_stage_m"] == pytest.approx(0.05 / (np.pi * 20), rel=0.05)


def test_cli_equals_python_api_on_the_same_config(tiny_run):
    from rockmass import solver
    from rockmass.blockgen import read_json
    from rockmass.config import load_config

    path, out, _ = tiny_run
    cfg = load_config(path)
    model = read_json(out / "blocks.json")
    result = solver.run(model, cfg.solve.to_settings(model, path))
    cli = json.loads((out / "result.json").read_text())
    api = result.to_json_dict()
    for a, c in zip(api["stages"], cli["stages"]):
        for key in ("steps", "status", "time_step_s", "max_displacement_m", "unbalanced_ratio"):
            assert a[key] == c[key], key
    assert api["max_displacement_m"] == cli["max_displacement_m"]
    final = result.frames[-1].position_m - model.centroid_xy_m
    with open(out / "history.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert float(rows[-1]["top_ux_m"]) == result.history["top_ux_m"][-1]
    assert np.isfinite(final).all()


def test_blocks_file_gives_the_same_run_as_the_blocks_section(tiny_run, tmp_path):
    path, out, _ = tiny_run
    text = path.read_text()
    solve_part = text[text.index("[solve]"):]
    cfg = _write(tmp_path, f'[solve]\nblocks_file = "{out / "blocks.json"}"\n'
                 + solve_part.removeprefix("[solve]\n"))
    out2 = tmp_path / "out"
    assert main(["solve", str(cfg), "--out", str(out2)]) == 0
    a = json.loads((out / "result.json").read_text())
    b = json.loads((out2 / "result.json").read_text())
    assert [s["steps"] for s in a["stages"]] == [s["steps"] for s in b["stages"]]
    assert a["max_displacement_m"] == b["max_displacement_m"]
    manifest = json.loads((out2 / "manifest.json").read_text())
    assert any(i["path"].endswith("blocks.json") for i in manifest["inputs"])


def test_soft_joints_overlap_exits_1_after_writing_everything(tmp_path, capsys):
    path = _tiny(tmp_path, kn="1e5", ks="1e5")
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "overlap" in err and str(path) in err
    result = _no_nan((out / "result.json").read_text())
    assert result["status"] == "overlap"
    assert "overlap" in result["diagnostic"] and "k_n" in result["diagnostic"]
    assert result["stages"][-1]["status"] == "overlap"
    assert {"history.csv", "blocks.pvd", "blocks.json", "manifest.json",
            "block_energy.csv"} <= {p.name for p in out.iterdir()}
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["extra"]["status"] == "overlap"


@pytest.mark.parametrize("old, new, field", [
    ('name = "gravity"', 'name = "gravity"\nknd = "static"', "solve.stages[0].knd"),
    ('kind = "dynamic"', 'kind = "quasi"', "solve.stages[1].kind"),
    ('model = "cy"', 'model = "barton"', "solve.joints.v"),
    ("kn_pa_m = 1e9", "kn_pa_m = -1e9", "solve.joints.default.kn_pa_m"),
    ("[solve.joints.default]", "[solve.joints.other]", "solve.joints"),
    ("duration_s = 0.12", "", "solve.stages[1].duration_s"),
    ('type = "sine", amplitude = 0.05,', 'type = "sine",', "solve.velocity_inputs[0].history"),
    ("block = 0", "block = 0\npoint_xy_m = [0.1, 0.1]", "solve.monitors[1].point_xy_m"),
])
def test_bad_config_exits_2_naming_the_field(tmp_path, capsys, old, new, field):
    text = TINY.format(kn="1e9", ks="5e8")
    assert old in text
    path = _write(tmp_path, text.replace(old, new, 1))
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and f"{field}" in err, err
    assert not out.exists()


def test_missing_blocks_exits_2(tmp_path, capsys):
    text = TINY.format(kn="1e9", ks="5e8")
    path = _write(tmp_path, text[text.index("[solve]"):])
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "solve.blocks_file" in err and "required" in err


def test_missing_blocks_file_exits_2(tmp_path, capsys):
    text = TINY.format(kn="1e9", ks="5e8")
    path = _write(tmp_path, '[solve]\nblocks_file = "nope.json"\n'
                  + text[text.index("[solve]"):].removeprefix("[solve]\n"))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "solve.blocks_file" in capsys.readouterr().err


def test_missing_solve_section_exits_2(tmp_path, capsys):
    text = TINY.format(kn="1e9", ks="5e8")
    path = _write(tmp_path, text[:text.index("[solve]")])
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "solve: required section is missing" in capsys.readouterr().err


def test_unknown_excavation_and_empty_selector_exit_2(tmp_path, capsys):
    path = _tiny(tmp_path, extra='[[solve.stages]]\nname = "dig"\nexcavate = ["tunnel"]\n')
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "solve.stages[2].excavate" in err and "tunnel" in err
    text = TINY.format(kn="1e9", ks="5e8").replace('where = "bottom"\n[[solve.velocity_inputs]]',
                                                   'where = "box:5,5,6,6"\n[[solve.velocity_inputs]]')
    path = _write(tmp_path, text, "d.toml")
    assert main(["solve", str(path), "--out", str(tmp_path / "out2")]) == 2
    assert str(path) in capsys.readouterr().err
    assert not (tmp_path / "out2").exists()


def test_joint_label_that_matches_no_contact_exits_2(tmp_path, capsys):
    path = _tiny(tmp_path, extra='[solve.joints.hh]\nmodel = "coulomb"\nkn_pa_m = 1e9\n'
                                  'ks_pa_m = 1e9\nfriction_deg = 20.0\n')
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "solve.joints.hh" in err and "'h'" in err


def test_csv_acceleration_history_is_integrated(tmp_path):
    from rockmass.solve_config import read_history_csv

    f = tmp_path / "acc.csv"
    f.write_text("time_s,acc_g\n0,1\n1,1\n2,1\n")
    v = read_history_csv(f, "acceleration", 9.81, "solve.velocity_inputs[0].history")
    assert v(np.array([0.5, 1.0, 2.0])) == pytest.approx([4.905, 9.81, 19.62])
    f.write_text("0,1\n1,x\n")
    with pytest.raises(ValueError, match=r"line 2"):
        read_history_csv(f, "velocity", 1.0, "solve.velocity_inputs[0].history")


def test_csv_history_in_a_config(tmp_path):
    (tmp_path / "v.csv").write_text("# table velocity\n0,0\n0.05,0.02\n0.1,0\n")
    text = TINY.format(kn="1e9", ks="5e8").replace(
        'history = { type = "sine", amplitude = 0.05, frequency_hz = 20.0, cycles = 2 }',
        'history = { type = "csv", file = "v.csv" }')
    path = _write(tmp_path, text)
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out), "--json"]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert any(i["path"].endswith("v.csv") for i in manifest["inputs"])
    # triangle of area 0.001 m: the base moved 1 mm and stayed there
    base = json.loads((out / "result.json").read_text())["monitors"]["base"]["stages"][-1]
    assert base["ux_m"] == pytest.approx(0.001, rel=0.03)


def test_every_section_maps_onto_the_solver_settings(tmp_path):
    """In-situ stress, boundary stress, quiet boundaries, a Ricker input, CY joints, rounding and
    the time-step safety reach :class:`rockmass.solver.Settings` unchanged, and the run works."""
    from rockmass import solver
    from rockmass.blockgen import read_json
    from rockmass.config import load_config

    text = TINY.format(kn="1e9", ks="5e8").replace(
        'history = { type = "sine", amplitude = 0.05, frequency_hz = 20.0, cycles = 2 }',
        'history = { type = "ricker", amplitude = 0.01, peak_frequency_hz = 30.0 }').replace(
        "[solve]\n", "[solve]\nrounding_m = 0.003\ntime_step_safety = 0.4\n"
                     "[solve.insitu]\nsxx_pa = 1e4\nsyy_pa = 2e4\n"
                     "[[solve.boundary_stress]]\nsides = [\"top\", \"left\", \"right\"]\n"
                     "from_insitu = true\n[solve.quiet]\nsides = [\"left\", \"right\"]\n").replace(
        "density_kg_m3 = 2700.0", "density_kg_m3 = 2700.0\nbulk_modulus_pa = 1e9\n"
                                  "shear_modulus_pa = 6e8")
    path = _write(tmp_path, text)
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out)]) == 0
    model = read_json(out / "blocks.json")
    st = load_config(path).solve.to_settings(model, path)
    assert st.insitu == solver.InSituStress(sxx_pa=1e4, syy_pa=2e4)
    assert st.boundary_stress == (solver.BoundaryStress(("top", "left", "right"), from_insitu=True),)
    assert st.quiet == solver.QuietBoundary(("left", "right"))
    assert st.material == solver.Material(2700.0, 1e9, 6e8)
    assert st.joints["v"] == solver.ContinuouslyYielding(1e9, 5e8)
    assert st.rounding_m == 0.003 and st.time_step_safety == 0.4
    assert st.velocity_inputs[0].history == solver.Ricker(0.01, 30.0)
    assert [s.kind for s in st.stages] == ["static", "dynamic"]
    result = json.loads((out / "result.json").read_text())
    assert result["status"] == "ok" and result["info"]["rounding_m"] == 0.003


def test_sample_configs_validate():
    from rockmass.config import load_config

    for name in ("solve_shaketable.toml", "solve_cavern.toml"):
        cfg = load_config(SAMPLES / name)
        assert cfg.solve is not None and cfg.blocks is not None
        assert len(cfg.solve.stages) >= 3


def test_cli_start_up_does_not_import_numpy():
    import subprocess
    import sys

    code = ("import sys; from rockmass.cli import build_parser; build_parser(); "
            "print('numpy' in sys.modules, 'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


def test_a_new_run_leaves_no_frame_of_an_earlier_run(tiny_run, tmp_path, capsys):
    """Frames of an earlier run with more frames would join the new ParaView series (issue 18)."""
    import shutil

    path, out, _ = tiny_run
    again = tmp_path / "out"
    shutil.copytree(out, again)
    stale = again / "blocks_0099.vtu"
    shutil.copy(again / "blocks_0000.vtu", stale)
    (again / "notes.txt").write_text("the user's own file")
    assert main(["solve", str(path), "--out", str(again)]) == 0
    capsys.readouterr()
    result = _no_nan((again / "result.json").read_text())
    frames = sorted(p.name for p in again.glob("blocks_*.vtu"))
    assert frames == [f["file"] for f in result["frames"]] and not stale.exists()
    assert (again / "notes.txt").read_text() == "the user's own file"


def test_contacts_vtu_holds_the_rows_of_contacts_csv(tiny_run):
    """contacts.vtu (issue 19): one vertex per row of contacts.csv at its point, with the stresses,
    plastic slip and flags of the row, the opening as the overlap sign-flipped and the force on
    block b as l (σ_n n − τ t); a stale one of an earlier run is the command's to remove; the frames
    carry ``excavated`` (nothing is excavated in this run)."""
    meshio = pytest.importorskip("meshio")
    from rockmass.solve_stage import _OWNED

    _, out, _ = tiny_run
    with open(out / "contacts.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    mesh = meshio.read(out / "contacts.vtu")
    d = mesh.point_data
    assert len(rows) > 10 and [c.type for c in mesh.cells] == ["vertex"] and len(mesh.points) == len(rows)

    def col(name):
        return np.array([float(r[name]) for r in rows])

    assert mesh.points[:, :2] == pytest.approx(np.column_stack([col("x_m"), col("y_m")]), rel=1e-12)
    for name in ("normal_stress_pa", "shear_stress_pa", "plastic_slip_m", "length_m", "block_a", "block_b"):
        assert d[name] == pytest.approx(col(name), rel=1e-12, abs=1e-300), name
    assert d["opening_m"] == pytest.approx(-col("overlap_m"), rel=1e-12, abs=1e-300)
    for name in ("slipping", "broken"):
        assert d[name].tolist() == [int(r[name] in ("1", "True", "true")) for r in rows], name
    n = np.column_stack([col("nx"), col("ny")])
    t = np.column_stack([-n[:, 1], n[:, 0]])
    force = col("length_m")[:, None] * (col("normal_stress_pa")[:, None] * n - col("shear_stress_pa")[:, None] * t)
    assert d["force_b_n_per_m"][:, :2] == pytest.approx(force, rel=1e-9, abs=1e-9 * np.abs(force).max())
    assert any(re.fullmatch(pattern, "contacts.vtu") for pattern in _OWNED)
    frame = meshio.read(out / "blocks_0000.vtu")
    assert not np.concatenate(frame.cell_data["excavated"]).any()


def test_monitor_point_outside_the_domain_exits_2_naming_it(tmp_path, capsys):
    """A point 480 m away used to follow the nearest block silently (issue 18)."""
    path = _tiny(tmp_path)
    path.write_text(path.read_text().replace("point_xy_m = [0.6, 0.4]", "point_xy_m = [480.6, 0.4]"))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "c.toml" in err and "monitor 'top'" in err and "outside the model domain" in err
    assert not (tmp_path / "out").exists()
