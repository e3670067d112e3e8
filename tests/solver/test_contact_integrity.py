"""Contact state that must survive a run (issue 14): a broken bond stays broken, and an in-situ start
is in moment equilibrium on supported sides too.

Every expected value is worked out here from the joint law or from statics, never copied from a
run; the values measured on the code before the fix are quoted in each docstring.
"""

from __future__ import annotations

import numpy as np
import pytest

from rockmass.solver import (BoundaryStress, Coulomb, Fix, InSituStress, Material, Monitor,
                             Settings, Stage, TableHistory, VelocityInput, run)
from rockmass.solver.engine import FREE, Engine
from rockmass.solver.loading import apply_boundary_stress, apply_insitu

from ._models import column, hand_model, jointed_rectangle, rect

G = 9.81


# ------------------------------------------------------------------- broken stays broken --
_SPEED = 0.01      # m/s, prescribed speed of the upper block
_UP = 0.011        # m, first pull: beyond the 0.01 m contact tolerance
_CLOSURE = 2e-4    # m, pushed back this far into the joint
_AGAIN = 5e-4      # m, second pull (beyond T/k_n of case (a))
_TOL = 0.01        # m, contact tolerance


def _pull_push_pull(kn: float, strength: float):
    """Block 1 (1 m × 1 m) glued on the fixed block 0 (cohesion = tension = ``strength``), moved
    by a prescribed vertical velocity (x and rotation fixed, no gravity): up ``_UP`` (beyond the
    contact tolerance: the contact opens), down to ``_CLOSURE`` into the joint, up again by
    ``_CLOSURE + _AGAIN``, in one dynamic stage of 20 000 steps (the velocity history runs on the
    stage's clock). Returns the result and the time the second pull starts."""
    t1 = _UP / _SPEED
    t2 = t1 + (_UP + _CLOSURE) / _SPEED
    t3 = t2 + (_CLOSURE + _AGAIN) / _SPEED
    e = 1e-9
    hist = TableHistory((0.0, t1, t1 * (1 + e), t2, t2 * (1 + e), 1.001 * t3),
                        (_SPEED, _SPEED, -_SPEED, -_SPEED, _SPEED, _SPEED))
    glued = Coulomb(kn, kn, 30.0, cohesion_pa=strength, tension_pa=strength)
    settings = Settings(joints={"default": glued}, material=Material(2000.0),
                        gravity_m_s2=(0.0, 0.0), contact_tolerance_m=_TOL,
                        fixes=(Fix("blocks:0"), Fix("blocks:1", "xr")),
                        velocity_inputs=(VelocityInput("blocks:1", "y", hist),),
                        monitors=(Monitor("top", block=1),),
                        stages=(Stage("cycle", "dynamic", duration_s=t3, time_step_s=t3 / 20_000,
                                      frames=0),))
    return run(column(1), settings), t2


def _check_stays_broken(result, t2, kn, released):
    """Broken once (both sub-contacts of the one face), no tension in the second pull, the
    elastic energy it held booked once as breakage, and the energy ledger closed."""
    st = result.stages[0]
    assert result.ok, result.diagnostic
    assert st.newly_broken_contacts == 2  # the face's two sub-contacts, once each
    assert st.broken_contacts == 1
    h = result.history
    fy = h["top_contact_fy_n"]  # contact force on block 1: > 0 pushes it up, < 0 holds it down
    assert fy.max() > 0.5 * kn * _CLOSURE * 1.0  # it did come back into compression
    # the broken joint has no tensile strength: pulling it apart again takes no force
    assert fy[h["time_s"] > t2].min() >= 0.0
    e = st.energy
    assert e["breakage_dissipation_j"] == pytest.approx(released, rel=0.02)
    return e["residual_j"] / (e["work_gravity_j"] + e["work_boundary_j"])


def test_broken_glued_contact_stays_broken_when_it_closes_again():
    """(a) T/k_n = 1e-4 m < tolerance: the bond breaks in tension at σ_n = −T and the blocks part
    beyond the tolerance. Coming back, the contact re-enters the detection range at a gap of the
    tolerance; re-activated intact it would pull at k_n × 0.01 m = 100 T and break again at once.
    It must close as the broken joint it is: broken once (2 sub-contacts, as before the fix: 4),
    breakage ½T²L/k_n = 5 J (before: 5.0e4 J, 1e4× the work in) and a ledger residual of 1.1 % of
    the work in (the tension break books the energy at the step that passes −T, first order in
    the step; before: −1e4×)."""
    kn, strength = 1e9, 1e5
    result, t2 = _pull_push_pull(kn, strength)
    residual = _check_stays_broken(result, t2, kn, 0.5 * strength ** 2 / kn * 1.0)
    assert abs(residual) < 0.03, residual


def test_bond_with_tension_above_the_tolerance_breaks_when_it_opens():
    """(b) T/k_n = 0.03 m > tolerance 0.01 m: the bond opens geometrically before its tension is
    exceeded (σ_n = −k_n × 0.01 m = T/3 there). A bond parted beyond the tolerance has failed in
    tension: it is broken there, its elastic energy ½ k_n tol² L = 5000 J booked as breakage
    (ledger residual 1.1e-4 of the work in), and it closes again broken. Before the fix it opened
    intact (0 broken), bonded again on closing and held the block back with up to 5.0e4 N in the
    second pull."""
    kn, strength = 1e8, 3e6
    assert strength / kn > _TOL
    result, t2 = _pull_push_pull(kn, strength)
    residual = _check_stays_broken(result, t2, kn, 0.5 * kn * _TOL ** 2 * 1.0)
    assert abs(residual) < 1e-3, residual


def test_a_frictional_joint_touched_at_a_corner_is_never_counted_broken():
    """A square tilted 30° dropped corner-first from 1 mm onto the base it shares a joint with
    (Coulomb, no cohesion or tension): the corner touches across the gap — a slot flagged as no
    bond — and the block bounces. A joint without strength has nothing to break: 0 broken
    contacts, 0 broken slots in the contact table (before the fix: 1, which made the zoned
    cavern report 28 "broken" joints that never held anything)."""
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    square = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]) @ [[c, s], [-s, c]]
    square[:, 1] += 1e-3 - square[:, 1].min()
    model = hand_model([rect(-5.0, -1.0, 5.0, 0.0), square], pairs=[(0, 1)])
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 40.0)}, material=Material(2500.0),
                        stages=(Stage("drop", "dynamic", duration_s=0.05),),
                        fixes=(Fix("blocks:0"),))
    result = run(model, settings)
    assert result.ok and result.displacement_m[1, 1] < -1e-3  # it fell onto its corner
    assert result.stages[0].broken_contacts == 0
    assert not result.contacts["broken"].any()


# ------------------------------------------------------- in-situ start in moment equilibrium --
def _roller_box_settings(max_steps: int = 1):
    """Gravity with K₀ = 0.5 written into the contacts, the overburden on the top as a traction,
    rollers on the bottom (y) and on the sides (x): the roller blocks are free to rotate."""
    return Settings(joints={"default": Coulomb(1e10, 5e9, 40.0)}, gravity_m_s2=(0.0, -G),
                    material=Material(2700.0),
                    insitu=InSituStress(sxx_pa=0.5e6, syy_pa=1e6, gravity_gradient=True, k0=0.5),
                    fixes=(Fix("bottom", "y"), Fix("left", "x"), Fix("right", "x")),
                    boundary_stress=(BoundaryStress(("top",), from_insitu=True),),
                    stages=(Stage("initial", max_steps=max_steps, tolerance=1e-30),))


def _first_step_unbalance(model, settings):
    """Per block, the first step's unbalanced force on its free translations and unbalanced moment
    (if its rotation is free), the set-up of :func:`rockmass.solver.run` repeated up to the first
    step's contact forces; each relative to the forces acting on the block (Σ|contact forces| +
    |weight| + |external force|), the moment as a force at the block's circumradius."""
    eng = Engine(model, settings)
    eng.detect()
    apply_insitu(eng, settings.insitu)
    apply_boundary_stress(eng, settings.boundary_stress, settings.insitu)
    eng.set_stage_modes(dynamic=False)
    eng.rebuild()
    eng.detect()
    force = np.zeros(eng.nb)
    moment = np.zeros(eng.nb)
    for b in range(eng.nb):
        applied = 0.0
        for e in eng.bp_idx[eng.bp_ptr[b]:eng.bp_ptr[b + 1]]:
            applied += np.hypot(*eng.fpair[e >> 1, 3 * (e & 1):3 * (e & 1) + 2])
        weight = eng.mass[b, :2] * eng.gravity
        applied += np.hypot(*weight) + np.hypot(*eng.ext_f[b])
        contact = eng.contact_force_on(b)
        free = eng.mode[b] == FREE
        unb = np.where(free[:2], contact[:2] + weight + eng.ext_f[b], 0.0)
        force[b] = np.hypot(*unb) / applied
        if free[2]:  # rotation 0 at the start: the external moment is ext_a
            moment[b] = abs(contact[2] + eng.ext_a[b]) / (applied * eng.radius[b])
    return force, moment, eng


def test_insitu_start_balances_the_moments_of_blocks_on_rollers():
    """Two joint sets at 30° and 115° cut irregular blocks along the rollers. The contacts carry
    the in-situ stress, the support carries the force of the missing boundary traction, but a
    roller does not hold the rotation: every block's first-step unbalanced force and moment
    (against the forces on it) must be at round-off, and a static stage must leave the blocks where
    they are. Measured: moment ratio 5e-13 and no motion (before: 0.14 on a bottom block, and the
    blocks moved 2.5e-5 m in 300 steps)."""
    model = jointed_rectangle()
    force, moment, eng = _first_step_unbalance(model, _roller_box_settings())
    on_roller = (eng.base_mode[:, :2] != FREE).any(axis=1)
    assert on_roller.sum() >= 6 and (eng.mode[on_roller, 2] == FREE).all()
    assert force.max() < 1e-9, force.max()
    assert moment.max() < 1e-9, (moment.argmax(), moment.max())
    result = run(model, _roller_box_settings(max_steps=300))
    assert result.ok, result.diagnostic
    # σ/k_n ~ 1e-4 m of joint closure: the blocks stay put to round-off
    assert np.abs(result.displacement_m).max() < 1e-12
    assert np.abs(result.rotation_rad).max() < 1e-12
