"""``rockmass solve`` with deformable blocks: zones.csv, zone cells in the frames, the zones'
summary in result.json (docs/dem.md §16.8), and the study's plastic-area column."""

from __future__ import annotations

import csv
import json

import meshio
import numpy as np

from rockmass.cli import main

# 2 x 2 blocks of 0.5 m on a fixed base row, the top right block zoned (Mohr–Coulomb, weak), a
# stress on the top that makes it yield
CONFIG = """[blocks]
[blocks.domain]
width_m = 1.0
height_m = 1.5
[[blocks.sets]]
name = "h"
angle_deg = 0.0
spacing_m = 0.5
origin_xy_m = [0.0, 0.0]
[[blocks.sets]]
name = "v"
angle_deg = 90.0
spacing_m = 0.5
origin_xy_m = [0.0, 0.0]

[solve]
gravity_m_s2 = [0.0, -9.81]
[solve.material]
density_kg_m3 = 2700.0
[solve.joints.default]
model = "coulomb"
kn_pa_m = 1e10
ks_pa_m = 5e9
friction_deg = 35.0
[[solve.fixes]]
where = "bottom"
[[solve.fixes]]
where = "left"
dofs = "x"
[[solve.fixes]]
where = "right"
dofs = "x"
[[solve.boundary_stress]]
sides = ["top"]
syy_pa = 3e6
[[solve.deformable]]
where = "box:0.5,1.0,1.0,1.5"
zone_size_m = 0.1
[solve.deformable.model]
model = "mohr_coulomb"
bulk_modulus_pa = 2e9
shear_modulus_pa = 1.2e9
cohesion_pa = 0.5e6
friction_deg = 30.0
tension_pa = 0.2e6
[[solve.monitors]]
name = "corner"
point_xy_m = [0.9, 1.4]
[[solve.stages]]
name = "load"
max_steps = 20000
frames = 2
"""


def test_solve_writes_the_zones_and_their_stress(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG)
    out = tmp_path / "run" / "solve"  # a run folder's solve stage: the report reads it
    assert main(["solve", str(cfg), "--out", str(out)]) == 0
    doc = json.loads((out / "result.json").read_text())
    zones = doc["zones"]
    assert zones["zones"] > 20 and zones["nodes"] > 20
    assert 0 < zones["plastic_area_m2"] <= 0.25 + 1e-9  # within the zoned block
    assert doc["info"]["deformable_blocks"] == 1
    rows = list(csv.DictReader((out / "zones.csv").open()))
    assert len(rows) == zones["zones"]
    area = sum(float(r["area_m2"]) for r in rows)
    assert abs(area - 0.25) < 0.01 * 0.25  # the zones tile the block (compressed a little)
    syy = np.array([float(r["syy_pa"]) for r in rows])
    assert 1e6 < np.mean(syy) < 6e6  # compression from the top stress, as the user reads it
    yielded = sum(float(r["area_m2"]) for r in rows if r["shear_past"] == "1"
                  or r["tension_past"] == "1")
    assert abs(yielded - zones["plastic_area_m2"]) < 1e-9
    energy = list(csv.DictReader((out / "block_energy.csv").open()))
    assert "parent_block" in energy[0]
    frame = meshio.read(out / "blocks_0001.vtu")
    names = set(frame.cell_data)
    assert {"stress_pa", "plastic_state", "yielded"} <= names
    state = np.concatenate(frame.cell_data["plastic_state"])
    assert (state == -1).sum() == 5 and (state >= 0).sum() == zones["zones"]  # 5 rigid blocks

    # the report's plastic-zone map (a run folder holding this solve stage)
    from rockmass.run_report import write_run_report

    report = write_run_report(tmp_path / "run").read_text()
    section = report[report.index('id="sec-plastic"'):]
    section = section[:section.index("</section>")]
    assert "data:image/png;base64," in section
    assert "Zones that yielded" in section and f"{zones['zones']} zones" in section


def test_solve_warns_when_the_zones_are_too_coarse_for_the_waves(tmp_path, capsys):
    """A 2 kHz shake of the zoned block (S wave λ = √(G/ρ)/f = 0.33 m, zones of 0.1 m: about three
    per wavelength): one plain warning line naming the zone size that would do, and the check in
    result.json (docs/dem.md §16.9)."""
    shake = CONFIG + """[[solve.velocity_inputs]]
where = "bottom"
component = "x"
history = { type = "sine", amplitude = 0.001, frequency_hz = 2000.0, cycles = 2 }
[[solve.stages]]
name = "shake"
kind = "dynamic"
duration_s = 0.001
frames = 0
"""
    cfg = tmp_path / "c.toml"
    cfg.write_text(shake)
    assert main(["solve", str(cfg), "--out", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    wavelength = (1.2e9 / 2700.0) ** 0.5 / 2000.0
    assert (f"rockmass: warning: stage 'shake': the zones of deformable[0]" in err
            and f"use zone_size_m <= {wavelength / 10:.3g} m" in err)
    check, = json.loads((tmp_path / "out" / "result.json").read_text())["info"]["wave_checks"]
    assert check["stage"] == "shake" and check["f_max_hz"] == 2000.0
    assert abs(check["wavelength_m"] - wavelength) < 1e-9 * wavelength
    assert 0.1 <= check["zone_size_m"] < 0.2 and check["zones_per_wavelength"] < 4
