"""ParaView outputs of a run (issue 19, item 6): ``contacts.vtu`` holds the contact slots at the end
with stresses, forces, slip and opening; the frames mark the excavated blocks.

The numbers are checked against statics worked out on paper (a block resting on an incline), not
against the solver's own table alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockmass.solver import Coulomb, Fix, Material, Settings, Stage, run
from rockmass.solver.vtu import CONTACT_POINT_DATA, FRAME_CELL_DATA, contact_mesh, frame_mesh, write_vtu

from ._models import hand_model, incline, rect

meshio = pytest.importorskip("meshio")

RHO, G, KN = 2500.0, 9.81, 1e9


def _read_contacts(result, tmp_path):
    path = write_vtu(contact_mesh(result.contacts), tmp_path / "contacts.vtu")
    return meshio.read(path)


def test_contacts_vtu_of_a_block_at_rest_on_an_incline_carries_its_weight(tmp_path):
    """Block 1 (1 m × 0.5 m, ρ = 2500 kg/m³) at rest on a 20° incline (friction 40°): the slots'
    forces on block 1 sum to its weight straight up, (0, ρ b h g) N/m; their normal and shear parts
    to m g cos ψ and m g sin ψ (shear positive: block 1 tends to move down-slope, along
    t = (−n_y, n_x)); each slot's opening is −σ_n / k_n (closure by the elastic joint, overlap
    sign-flipped); the points lie on the base of block 1 and nothing slips."""
    psi, b, h = 20.0, 1.0, 0.5
    settings = Settings(joints={"default": Coulomb(KN, KN, 40.0)}, material=Material(RHO),
                        fixes=(Fix("blocks:0"),), stages=(Stage("settle", tolerance=1e-7),))
    result = run(incline(psi, b, h), settings)
    assert result.ok
    mesh = _read_contacts(result, tmp_path)
    assert tuple(mesh.point_data) == CONTACT_POINT_DATA
    assert [c.type for c in mesh.cells] == ["vertex"] and len(mesh.points) == len(result.contacts["x_m"]) == 2
    d = mesh.point_data
    weight = RHO * b * h * G
    c, s = math.cos(math.radians(psi)), math.sin(math.radians(psi))
    assert d["block_a"].tolist() == [0, 0] and d["block_b"].tolist() == [1, 1]
    assert d["normal"] == pytest.approx(np.tile([-s, c, 0.0], (2, 1)), abs=1e-9)
    assert d["force_b_n_per_m"].sum(axis=0) == pytest.approx([0.0, weight, 0.0], abs=1e-4 * weight)
    assert (d["normal_stress_pa"] * d["length_m"]).sum() == pytest.approx(weight * c, rel=1e-4)
    assert (d["shear_stress_pa"] * d["length_m"]).sum() == pytest.approx(weight * s, rel=1e-4)
    assert d["length_m"].sum() == pytest.approx(b, rel=1e-3)
    assert d["opening_m"] == pytest.approx(-d["normal_stress_pa"] / KN, rel=1e-6)
    assert (d["opening_m"] < 0).all() and d["slipping"].tolist() == [0, 0]
    assert d["plastic_slip_m"].tolist() == [0.0, 0.0]
    # the points: at the two ends of block 1's base (through the origin, along the slope; the
    # block has moved by microns), z = 0; the forces there turn block 1 about its centroid by 0
    xy = mesh.points[:, :2]
    along, across = xy @ [c, s], xy @ [-s, c]
    assert sorted(along.tolist()) == pytest.approx([-b / 2, b / 2], abs=1e-4)
    assert np.abs(across).max() < 1e-4 and mesh.points[:, 2].tolist() == [0.0, 0.0]
    arm = xy - (incline(psi, b, h).centroid_xy_m[1] + result.displacement_m[1])
    force = d["force_b_n_per_m"][:, :2]
    assert abs((arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]).sum()) < 1e-6 * weight * b


def test_contacts_vtu_of_a_sliding_block_is_at_its_coulomb_strength(tmp_path):
    """Block 1 sliding down a 30° incline with friction 20°: every slot slips, |τ| = σ_n tan φ,
    the plastic slip has grown, and the mesh holds the solver's table value for value."""
    settings = Settings(joints={"default": Coulomb(KN, KN, 20.0)}, material=Material(RHO),
                        fixes=(Fix("blocks:0"),), stages=(Stage("slide", "dynamic", duration_s=0.05),))
    result = run(incline(30.0, vertical_sides=True), settings)
    d = _read_contacts(result, tmp_path).point_data
    table = result.contacts
    assert len(d["slipping"]) == 2 and d["slipping"].tolist() == [1, 1]
    assert np.abs(d["shear_stress_pa"]) == pytest.approx(d["normal_stress_pa"] * math.tan(math.radians(20.0)),
                                                         rel=1e-9)
    assert (d["plastic_slip_m"] > 0).all()
    for name in ("normal_stress_pa", "shear_stress_pa", "plastic_slip_m", "length_m"):
        assert d[name].tolist() == table[name].tolist(), name
    assert d["opening_m"].tolist() == (-table["overlap_m"]).tolist()
    assert d["broken"].tolist() == table["broken"].astype(int).tolist()


def test_contacts_vtu_without_contacts_is_an_empty_mesh(tmp_path):
    mesh = contact_mesh({})
    assert mesh.points.shape == (0, 3) and set(mesh.point_data) == set(CONTACT_POINT_DATA)
    text = write_vtu(mesh, tmp_path / "contacts.vtu").read_text()
    assert 'NumberOfPoints="0"' in text


def _dig_model():
    """Block 0 a fixed base [0, 4] × [−1, 0]; block 1 [0, 2] × [0, 1] (rock) and block 2 [2, 4] ×
    [0, 1] (excavation stage 1) on it; block 3 a 0.2 m square far to the side at y = 3, touching
    nothing: it falls in the first stage and is taken out as failed."""
    polys = [rect(0, -1, 4, 0), rect(0, 0, 2, 1), rect(2, 0, 4, 1), rect(8, 3, 8.2, 3.2)]
    return hand_model(polys, [(0, 1), (0, 2), (1, 2)], region=np.array([0, 0, 1, 0]),
                      domain_xy_m=rect(0, -1, 10, 4))


@pytest.mark.filterwarnings("ignore:.* of the opening of regions:UserWarning")  # a toy opening at the edge
def test_frames_mark_excavated_blocks_apart_from_failed_ones():
    """Before the excavation stage no block is marked; after it block 2 (region 1) is ``excavated``
    and the falling block 3, taken out as failed, is ``failed`` and not ``excavated``; the frame's
    cell data keep the earlier names in order with ``excavated`` appended."""
    settings = Settings(joints={"default": Coulomb(KN, KN, 40.0)}, material=Material(RHO),
                        fixes=(Fix("blocks:0"),),
                        stages=(Stage("settle", max_steps=20_000, frames=2), Stage("dig", excavate=(1,))))
    model = _dig_model()
    result = run(model, settings)
    assert FRAME_CELL_DATA[:7] == ("displacement", "velocity", "rotation_rad", "block_id", "region", "active",
                                   "failed") and FRAME_CELL_DATA[7] == "excavated"

    def marks(frame):
        mesh = frame_mesh(model, frame)
        assert tuple(mesh.cell_data) == FRAME_CELL_DATA
        ids = np.concatenate(mesh.cell_data["block_id"])
        order = np.argsort(ids)
        return {name: np.concatenate(mesh.cell_data[name])[order].tolist()
                for name in ("excavated", "failed", "active")}

    first = marks(result.frames[0])
    settled = marks(next(f for f in reversed(result.frames) if f.stage == "settle"))
    last = marks(result.frames[-1])
    assert first["excavated"] == [0, 0, 0, 0]
    assert settled == {"excavated": [0, 0, 0, 0], "failed": [0, 0, 0, 1], "active": [1, 1, 1, 0]}
    assert last == {"excavated": [0, 0, 1, 0], "failed": [0, 0, 0, 1], "active": [1, 1, 0, 0]}
