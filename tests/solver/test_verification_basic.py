"""DEM verification against closed forms: docs/dem.md §13, problems 1–5, 9 and 10.

Every expected value is computed here from the closed form (never copied from a run). Tolerances
are stated next to each check with what limits them: the central-difference period error
(ωΔt)²/24, the static convergence tolerance, one step of elastic loading at a failure, the elastic
joint that a rigid-plastic closed form ignores.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockmass.blockgen import JointSet, build
from rockmass.solver import (BoundaryStress, Coulomb, Fix, InSituStress, Material, Monitor,
                             Settings, Stage, TableHistory, VelocityInput, run)

from ._models import column, incline, jointed_rectangle, rect, shear_box

G = 9.81
RHO = 2000.0


def _rad(deg):
    return math.radians(deg)


# ------------------------------------------------------------------ 1. block on an incline --
def _incline_settings(joint, stages, **kw):
    return Settings(joints={"default": joint}, stages=stages, material=Material(RHO),
                    fixes=(Fix("blocks:0"),), monitors=(Monitor("top", block=1),), **kw)


@pytest.mark.parametrize("psi", [20.0, 29.0])
def test_incline_static_below_friction_angle(psi):
    """ψ < φ: the block settles on the joint (elastic shear only) and then stays put."""
    phi = 30.0
    stages = (Stage("settle"), Stage("hold", "dynamic", duration_s=0.2))
    r = run(incline(psi), _incline_settings(Coulomb(1e9, 1e9, phi), stages))
    settle, hold = r.stages
    assert settle.converged
    # elastic shear displacement W sin ψ/(k_s b) ~ 2.5e-6 m; the static transient adds a little
    assert settle.max_displacement_m < 1e-4
    assert hold.max_displacement_stage_m < 1e-7
    assert hold.slipping_contacts == 0


@pytest.mark.parametrize("psi, phi", [(30.0, 20.0), (40.0, 10.0), (25.0, 20.0)])
def test_incline_sliding_acceleration(psi, phi):
    """ψ > φ: the block slides down with a = g(sin ψ − cos ψ tan φ), within 1 %."""
    duration = 0.2
    stages = (Stage("slide", "dynamic", duration_s=duration, history_every=1),)
    r = run(incline(psi), _incline_settings(Coulomb(1e9, 1e9, phi), stages))
    h = r.history
    down_slope = -(h["top_vx_m_s"] * math.cos(_rad(psi)) + h["top_vy_m_s"] * math.sin(_rad(psi)))
    late = h["time_s"] > duration / 2  # after the landing transient
    a = np.polyfit(h["time_s"][late], down_slope[late], 1)[0]
    expected = G * (math.sin(_rad(psi)) - math.cos(_rad(psi)) * math.tan(_rad(phi)))
    assert a == pytest.approx(expected, rel=0.01)  # measured 0.01–0.35 %


@pytest.mark.parametrize("factor, holds", [(0.98, False), (1.02, True)])
def test_incline_cohesion_onset(factor, holds):
    """Onset of sliding when c b + W cos ψ tan φ = W sin ψ: 2 % below the critical cohesion the
    block slides, 2 % above it holds.

    The block has vertical sides (its weight acts straight above the middle of its base, so the
    normal stress is uniform, as the closed form assumes) and starts from the in-situ stress
    σ_yy = W/(b cos ψ), whose traction on the base is exactly the weight (σ_n = W cos ψ/b,
    τ = W sin ψ/b): without it the sudden application of gravity overshoots (the static stage
    from zero contact force holds only above about 1.5× the critical cohesion).
    """
    psi, phi, b, h = 30.0, 20.0, 1.0, 0.5
    model = incline(psi, b, h, vertical_sides=True)
    weight = RHO * model.area_m2[1] * G
    c_crit = weight * (math.sin(_rad(psi)) - math.cos(_rad(psi)) * math.tan(_rad(phi))) / b
    joint = Coulomb(1e9, 1e9, phi, cohesion_pa=factor * c_crit)
    stages = (Stage("settle", max_steps=10_000), Stage("after", "dynamic", duration_s=0.1))
    r = run(model, _incline_settings(joint, stages,
                                     insitu=InSituStress(syy_pa=weight / (b * math.cos(_rad(psi))))))
    settle, after = r.stages
    if holds:
        assert settle.converged and settle.broken_contacts == 0
        assert after.max_displacement_m < 1e-6
    else:  # it slides away: named as a failed block, not measured as a displacement
        assert settle.status == "failed_blocks" and settle.broken_contacts > 0
        assert [(f["block"], f["mechanism"]) for f in settle.failed_blocks] == [(1, "slide")]
        assert settle.max_displacement_m == 0.0  # the base, the only block left, is fixed


@pytest.mark.parametrize("b, topples", [(0.8, False), (0.4, True)])
def test_incline_toppling(b, topples):
    """ψ < φ (no sliding): the block of height h topples iff b/h < tan ψ."""
    psi, phi, h = 30.0, 40.0, 1.0
    assert (b / h < math.tan(_rad(psi))) == topples
    stages = (Stage("settle", max_steps=10_000),)
    r = run(incline(psi, b, h), _incline_settings(Coulomb(1e9, 1e9, phi), stages))
    if topples:  # it falls onto its side: a failed block, by rotation
        assert [(f["block"], f["mechanism"]) for f in r.stages[0].failed_blocks] == [(1, "rotation")]
        assert abs(r.rotation_rad[1]) > 0.05
    else:
        assert r.stages[0].converged
        assert abs(r.rotation_rad[1]) < 1e-3


# --------------------------------------------------------------------- 2. Newmark block --
@pytest.mark.parametrize("start", ["insitu", "static"])
@pytest.mark.parametrize("ratio, t0", [(2.0, 0.1), (4.0, 0.05)])
def test_newmark_permanent_slip(ratio, t0, start):
    """Base acceleration A = ratio · a_y for t₀, then constant base velocity V = A t₀: the block
    (friction μ, a_y = μ g) slips d = (V²/2a_y)(1 − a_y/A) relative to the base, within 1 %.

    The joint is elastic before it slips, so the block starts sliding a little late (about A/ω
    of velocity lag): the slip exceeds the rigid-plastic d by ~0.2–0.5 % with k = 1e10 Pa/m.
    The block starts on its in-situ stress σ_yy = W/b (no landing transient) or settles in a
    static stage first (the input then starts at t = 0 of the dynamic stage).
    """
    phi, b, h = 15.0, 1.0, 0.5
    a_y = G * math.tan(_rad(phi))
    A = ratio * a_y
    V = A * t0
    duration = t0 + 1.5 * V / a_y  # slip ends at V/a_y
    base_velocity = TableHistory((0.0, t0, 10 * duration), (0.0, V, V))
    shake = Stage("shake", "dynamic", duration_s=duration)
    st = Settings(joints={"default": Coulomb(1e10, 1e10, phi)},
                  stages=(shake,) if start == "insitu" else (Stage("settle"), shake),
                  material=Material(RHO), fixes=(Fix("blocks:0", "yr"),),
                  velocity_inputs=(VelocityInput("blocks:0", "x", base_velocity),),
                  monitors=(Monitor("block", block=1), Monitor("base", block=0)),
                  insitu=InSituStress(syy_pa=RHO * h * G) if start == "insitu" else None)
    r = run(incline(0.0, b, h), st)
    assert r.ok
    hist = r.history
    # the base follows its input: ∫v dt = V (T − t₀/2)
    assert hist["base_ux_m"][-1] == pytest.approx(V * (duration - t0 / 2), rel=1e-3)
    slip = hist["base_ux_m"][-1] - hist["block_ux_m"][-1]
    expected = V ** 2 / (2 * a_y) * (1 - a_y / A)
    assert slip == pytest.approx(expected, rel=0.01)  # measured +0.2 % (ratio 4), +0.44 % (2)
    assert hist["block_vx_m_s"][-1] == pytest.approx(V, rel=0.01)  # moves with the base again


def test_velocity_input_starts_with_the_dynamic_stage():
    """A velocity history starts at t = 0 of the dynamic stage, also after a static stage:
    a ramp 0 → 1 m/s over 0.1 s moves the base 0.05 m in 0.1 s."""
    ramp = TableHistory((0.0, 0.1, 10.0), (0.0, 1.0, 1.0))
    st = Settings(joints={"default": Coulomb(1e9, 1e9, 15.0)},
                  stages=(Stage("settle"), Stage("shake", "dynamic", duration_s=0.1)),
                  material=Material(RHO), fixes=(Fix("blocks:0", "yr"),),
                  velocity_inputs=(VelocityInput("blocks:0", "x", ramp),),
                  monitors=(Monitor("base", block=0),))
    r = run(incline(0.0), st)
    assert r.stages[0].simulated_time_s > 0.01  # the static stage did take pseudo-time
    assert r.history["base_ux_m"][-1] == pytest.approx(0.5 * 1.0 * 0.1, rel=0.01)


# ------------------------------------------------------- 3. free vertical vibration on a joint --
def test_vertical_vibration_frequency():
    """A block dropped onto a joint under gravity oscillates about the static closure
    δ = mg/(k_n b) with ω = √(k_n b/m): period within 1 % of 2π/ω, and within 0.05 % of the
    central-difference period 2π/ω_h, sin(ω_h Δt/2) = ωΔt/2 (shorter by ≈ (ωΔt)²/24)."""
    b, h, kn = 1.0, 0.5, 1e9
    m = RHO * b * h
    omega = math.sqrt(kn * b / m)
    delta = m * G / (kn * b)
    st = Settings(joints={"default": Coulomb(kn, kn, 40.0)},
                  stages=(Stage("free", "dynamic", duration_s=0.05, history_every=1),),
                  material=Material(RHO), fixes=(Fix("blocks:0"),), monitors=(Monitor("top", block=1),),
                  time_step_safety=0.2)
    r = run(incline(0.0, b, h), st)
    t, uy = r.history["time_s"], r.history["top_uy_m"]
    y = uy + delta
    up = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    crossings = t[up] - y[up] * (t[up + 1] - t[up]) / (y[up + 1] - y[up])
    assert len(crossings) >= 5
    period = np.diff(crossings).mean()
    assert period == pytest.approx(2 * math.pi / omega, rel=0.01)  # measured −0.12 %
    dt = r.stages[0].time_step_s
    omega_h = 2 * math.asin(omega * dt / 2) / dt
    assert period == pytest.approx(2 * math.pi / omega_h, rel=5e-4)
    # undamped: oscillates between 0 and 2δ about δ, without sliding or rocking
    assert uy.mean() == pytest.approx(-delta, rel=0.01)
    assert uy.min() == pytest.approx(-2 * delta, rel=0.01)
    assert np.abs(r.history["top_ux_m"]).max() < 1e-3 * delta
    assert np.abs(r.history["top_rotation_rad"]).max() < 1e-3 * delta / b


def test_static_closure_under_gravity():
    """Static closure of a block on a joint: δ = mg/(k_n b)."""
    b, h, kn = 1.0, 0.5, 1e9
    st = Settings(joints={"default": Coulomb(kn, kn, 40.0)}, stages=(Stage("settle", tolerance=1e-7),),
                  material=Material(RHO), fixes=(Fix("blocks:0"),), monitors=(Monitor("top", block=1),))
    r = run(incline(0.0, b, h), st)
    assert r.stages[0].converged
    assert r.history["top_uy_m"][-1] == pytest.approx(-RHO * b * h * G / (kn * b), rel=1e-5)


# ------------------------------------------------------------------------ 4. block column --
@pytest.mark.parametrize("n", [1, 3, 8])
def test_column_settlement(n):
    """N blocks on N joints in series under σ on top (no gravity): the top settles σN/k_n and block
    k by σk/k_n, to the convergence tolerance (1e-7 → relative error < 1e-5)."""
    kn, sigma = 1e9, 2e6
    st = Settings(joints={"default": Coulomb(kn, kn, 40.0)}, stages=(Stage("load", tolerance=1e-7),),
                  gravity_m_s2=(0.0, 0.0), material=Material(RHO), fixes=(Fix("blocks:0"),),
                  boundary_stress=(BoundaryStress(("top",), syy_pa=sigma),),
                  monitors=(Monitor("top", block=n),))
    r = run(column(n), st)
    assert r.stages[0].converged
    assert r.history["top_uy_m"][-1] == pytest.approx(-sigma * n / kn, rel=1e-5)
    expected = -sigma * np.arange(n + 1) / kn
    np.testing.assert_allclose(r.displacement_m[:, 1], expected, rtol=1e-5, atol=1e-12)
    np.testing.assert_allclose(r.displacement_m[:, 0], 0.0, atol=1e-12)


# --------------------------------------------------------------------- 5. direct shear --
def test_direct_shear_coulomb_constant_normal_load():
    """CNL: σ_n applied on the upper half, which is sheared at constant velocity over the longer
    lower half (the contact length stays b): τ peaks at c + σ_n tan φ (brittle: c → 0 on failure)
    and then stays at σ_n tan φ. The recorded peak is the last elastic step before failure, so it
    may be short of the strength by one step of loading, k_s v Δt."""
    b, h = 1.0, 0.5
    sigma, c, phi, kn, ks, v = 1e6, 0.2e6, 30.0, 1e10, 1e9, 0.01
    st = Settings(joints={"default": Coulomb(kn, ks, phi, cohesion_pa=c)}, gravity_m_s2=(0.0, 0.0),
                  stages=(Stage("load"), Stage("shear", "dynamic", duration_s=0.3, history_every=1)),
                  material=Material(RHO), fixes=(Fix("blocks:0"), Fix("blocks:1", "r")),
                  velocity_inputs=(VelocityInput("blocks:1", "x", TableHistory((0.0, 1e3), (v, v))),),
                  boundary_stress=(BoundaryStress(("top",), syy_pa=sigma),),
                  monitors=(Monitor("top", block=1),))
    r = run(shear_box(b, h), st)
    load, shear = r.stages
    assert load.converged
    hist = r.history
    on = hist["stage"] == "shear"
    tau = -hist["top_contact_fx_n"][on] / b  # the joint resists the +x motion of the upper half
    assert hist["top_ux_m"][on][-1] == pytest.approx(v * shear.simulated_time_s, rel=1e-6)
    peak = c + sigma * math.tan(_rad(phi))
    one_step = ks * v * shear.time_step_s
    assert peak - 1.01 * one_step <= tau.max() <= peak * (1 + 1e-6)  # measured −0.33 %
    residual = sigma * math.tan(_rad(phi))
    assert tau[-1] == pytest.approx(residual, rel=1e-4)  # σ_n to the static tolerance: −2e-5
    # constant normal stress, no dilation: the normal force stays σ_n b
    assert hist["top_contact_fy_n"][on] == pytest.approx(np.full(on.sum(), sigma * b), rel=1e-4)
    contacts = r.contacts
    assert contacts["broken"].all() and contacts["slipping"].all()
    # plastic slip = shear displacement − elastic part τ/k_s (the contact state is that of the
    # last force evaluation, one step of motion, v Δt, behind the block)
    np.testing.assert_allclose(contacts["plastic_slip_m"],
                               v * shear.simulated_time_s - residual / ks,
                               atol=1.01 * v * shear.time_step_s)


def test_direct_shear_coulomb_constant_normal_stiffness():
    """CNS: the upper half is held between the shear joint (k_n, dilation ψ) and a normal spring of
    stiffness K (a joint to a cap block that moves with it in x and is fixed in y). Slip dilates the
    joint by tan ψ per unit plastic slip u_p; with the spring and the joint in series
    σ_n = σ_n0 + K_eff tan ψ u_p, K_eff = K k_n/(K + k_n), τ = σ_n tan φ while slipping, so τ rises
    linearly with the shear displacement u_s at slope a/(1 + a/k_s), a = K_eff tan ψ tan φ
    (docs/dem.md §13, problem 5). The sample rises by k_n tan ψ u_p/(k_n + K).

    σ_n0 comes from the in-situ stress in both joints (equilibrium at the start, no gravity); a slow
    shear (1 mm/s) keeps the undamped normal oscillation of the sample small (< 0.1 % of Δσ_n).
    """
    b, h = 1.0, 0.5
    sigma0, phi, psi, kn, ks, K, v = 1e6, 30.0, 10.0, 1e10, 1e9, 2e9, 1e-3
    duration = 3.0
    st = Settings(joints={"default": Coulomb(kn, ks, phi),
                          "shear": Coulomb(kn, ks, phi, dilation_deg=psi),
                          "cap": Coulomb(K, K, phi)},
                  gravity_m_s2=(0.0, 0.0), material=Material(RHO),
                  stages=(Stage("shear", "dynamic", duration_s=duration),),
                  insitu=InSituStress(syy_pa=sigma0),
                  fixes=(Fix("blocks:0"), Fix("blocks:1", "r"), Fix("blocks:2", "yr")),
                  velocity_inputs=(VelocityInput("blocks:1,2", "x",
                                                 TableHistory((0.0, 1e3), (v, v))),),
                  monitors=(Monitor("sample", block=1),))
    r = run(shear_box(b, h, cap_stiff=True), st)
    assert r.ok
    c = r.contacts
    joint = (c["block_a"] == 0) & (c["block_b"] == 1)
    cap = (c["block_a"] == 1) & (c["block_b"] == 2)
    assert joint.sum() == 2 and cap.sum() == 2
    tan_phi, tan_psi = math.tan(_rad(phi)), math.tan(_rad(psi))
    k_eff = K * kn / (K + kn)
    u_p = c["plastic_slip_m"][joint]
    assert (u_p > 1e-3).all()
    d_sigma = k_eff * tan_psi * u_p
    np.testing.assert_allclose(c["normal_stress_pa"][joint] - sigma0, d_sigma, rtol=2e-3)
    np.testing.assert_allclose(c["normal_stress_pa"][cap] - sigma0, d_sigma, rtol=2e-3)
    # at the strength (to the small normal oscillation: measured 1e-4)
    np.testing.assert_allclose(np.abs(c["shear_stress_pa"][joint]),
                               c["normal_stress_pa"][joint] * tan_phi, rtol=1e-3)
    np.testing.assert_allclose(c["shear_stress_pa"][cap], 0.0, atol=1e-6 * sigma0)
    hist = r.history
    assert hist["sample_uy_m"][-1] == pytest.approx(kn * tan_psi * u_p.mean() / (kn + K), rel=2e-3)
    tau = -hist["sample_contact_fx_n"] / b
    us = hist["sample_ux_m"]
    slipping = us > 0.5 * us.max()  # well past the elastic part (τ₀/k_s ≈ 0.6 mm of 3 mm)
    slope = np.polyfit(us[slipping], tau[slipping], 1)[0]
    a = k_eff * tan_psi * tan_phi
    assert slope == pytest.approx(a / (1 + a / ks), rel=5e-3)


# -------------------------------------------------------------------------- 9. time step --
def _block_on_spring_omega_max(b, h, kn, ks, m):
    """ω_max of a b × h block on a fixed base through two corner springs (each k l, l = b/2):
    dofs (u, v, θ); normal springs at x = ±b/2 and shear springs at y = −h/2 from the centroid."""
    stiffness = np.zeros((3, 3))
    for rx in (-b / 2, b / 2):
        g_n = np.array([0.0, 1.0, rx])       # normal closure  = v + θ r_x
        g_s = np.array([1.0, 0.0, h / 2])    # shear slip      = u − θ r_y, r_y = −h/2
        stiffness += kn * b / 2 * np.outer(g_n, g_n) + ks * b / 2 * np.outer(g_s, g_s)
    mass = np.diag([m, m, m * (b * b + h * h) / 12])
    return math.sqrt(np.linalg.eigvals(np.linalg.solve(mass, stiffness)).real.max())


def _spring_settings(kn, ks, stage, **kw):
    return Settings(joints={"default": Coulomb(kn, ks, 40.0)}, stages=(stage,),
                    material=Material(RHO), fixes=(Fix("blocks:0"),),
                    monitors=(Monitor("top", block=1),), **kw)


def test_automatic_time_step_below_the_true_limit():
    """The automatic step and the reported limit are ≤ 2/ω_max of the hand-computed 3-dof system
    (translation and rotation coupled through the shear springs), and the limit is not wastefully
    conservative (≥ half of the true one)."""
    from rockmass.solver import Engine

    b, h, kn, ks = 1.0, 0.5, 1e9, 4e8
    true_limit = 2.0 / _block_on_spring_omega_max(b, h, kn, ks, RHO * b * h)
    stage = Stage("free", "dynamic", duration_s=0.01)
    model = incline(0.0, b, h)
    settings = _spring_settings(kn, ks, stage)
    eng = Engine(model, settings)
    eng.detect()
    limit = eng.stable_time_step()
    assert 0.5 * true_limit <= limit <= true_limit  # measured 0.73
    r = run(model, settings)
    assert r.stages[0].stable_time_step_s == pytest.approx(limit, rel=1e-12)
    assert r.stages[0].time_step_s == pytest.approx(settings.step_safety(dynamic=True) * limit, rel=1e-12)


@pytest.mark.parametrize("factor, stable", [(0.97, True), (1.03, False)])
def test_stability_boundary_is_two_over_omega_max(monkeypatch, factor, stable):
    """Central difference is stable iff Δt ≤ 2/ω_max: with the solver's (conservative) refusal
    switched off, a glued block on an incline runs at 0.97 of the hand-computed 2/ω_max with
    bounded energy and blows up within a few dozen steps at 1.03 (the run stops with a failed
    status, overlap or non-finite, instead of returning garbage)."""
    from rockmass.solver import Engine

    psi, b, h, kn, ks = 20.0, 1.0, 0.5, 1e9, 4e8
    true_limit = 2.0 / _block_on_spring_omega_max(b, h, kn, ks, RHO * b * h)
    monkeypatch.setattr(Engine, "stable_time_step", lambda self, beta=0.0: math.inf)
    glued = Coulomb(kn, ks, 40.0, cohesion_pa=1e9, tension_pa=1e9)
    stage = Stage("shake", "dynamic", duration_s=0.3, time_step_s=factor * true_limit,
                  history_every=1)
    r = run(incline(psi, b, h), Settings(joints={"default": glued}, stages=(stage,),
                                         material=Material(RHO), fixes=(Fix("blocks:0"),)))
    s = r.stages[0]
    ke = r.history["kinetic_energy_j"]
    assert np.isfinite(ke).all() and np.isfinite(r.displacement_m).all()
    if stable:
        assert s.status == "completed"
        half = len(ke) // 2
        assert ke[half:].max() <= 1.5 * ke[:half].max()
    else:
        assert s.status in ("overlap", "unstable") and s.diagnostic
        assert s.steps < 200


@pytest.mark.parametrize("factor, decays", [(0.97, True), (1.03, False)])
def test_stability_boundary_with_stiffness_damping(monkeypatch, factor, decays):
    """Stiffness-proportional Rayleigh damping β lowers the limit to (2/ω)(√(1 + ξ²) − ξ),
    ξ = βω_max/2 (docs/dem.md §2.3, eq. (2.6)). With ξ = 0.5 on the fastest mode: the engine's damped limit is
    below it, and with the refusal switched off the motion decays at 0.97 of it (kinetic energy
    down by > 1e10) but not at 1.03 (the fastest mode grows without bound until the overlap
    limit stops the run)."""
    from rockmass.solver import Engine

    psi, b, h, kn, ks = 20.0, 1.0, 0.5, 1e9, 4e8
    omega_max = _block_on_spring_omega_max(b, h, kn, ks, RHO * b * h)
    beta = 1.0 / omega_max
    xi = 0.5 * beta * omega_max
    limit = 2.0 / omega_max * (math.sqrt(1.0 + xi * xi) - xi)
    xi_f = 0.1  # stiffness only: β = 2ξ_f/ω_f
    f_hz = 2 * xi_f / beta / (2 * math.pi)
    glued = Coulomb(kn, ks, 40.0, cohesion_pa=1e9, tension_pa=1e9)

    def settings(dt):
        stage = Stage("shake", "dynamic", duration_s=0.3, time_step_s=dt, history_every=1,
                      rayleigh_ratio=xi_f, rayleigh_frequency_hz=f_hz, rayleigh_mode="stiffness")
        return Settings(joints={"default": glued}, stages=(stage,), material=Material(RHO),
                        fixes=(Fix("blocks:0"),))

    model = incline(psi, b, h)
    eng = Engine(model, settings(None))
    eng.detect()
    assert eng.stable_time_step(beta) <= limit  # measured 0.62
    monkeypatch.setattr(Engine, "stable_time_step", lambda self, beta=0.0: math.inf)
    r = run(model, settings(factor * limit))
    ke = r.history["kinetic_energy_j"]
    assert np.isfinite(ke).all()
    if decays:
        assert r.stages[0].status == "completed"
        assert ke[-1] < 1e-10 * ke.max()
    else:
        assert r.stages[0].status in ("overlap", "unstable") and r.stages[0].diagnostic
        assert ke[-1] > 1e3 * ke[1]


def test_user_time_step_above_the_limit_is_refused():
    """A user Δt above the stable limit raises ValueError naming the limit."""
    from rockmass.solver import Engine

    kn = ks = 1e9
    model = incline(0.0)
    eng = Engine(model, _spring_settings(kn, ks, Stage("s", "dynamic", duration_s=0.01)))
    eng.detect()
    limit = eng.stable_time_step()
    too_big = Stage("s", "dynamic", duration_s=0.01, time_step_s=1.01 * limit)
    with pytest.raises(ValueError, match="stable limit") as err:
        run(model, _spring_settings(kn, ks, too_big))
    assert f"{limit:.6g}" in str(err.value)


def test_user_time_step_at_0p9_of_the_limit_is_stable():
    """At 0.9 of the limit, undamped and glued (linear elastic: no slip, no opening), a block on an
    incline (all three modes excited) oscillates for ~100 periods of the fastest mode with bounded
    energy: the kinetic energy never exceeds the potential energy gravity can release,
    W·(2 × a bound of the static displacement), and the second half is no more energetic than the
    first."""
    from rockmass.solver import Engine

    psi, b, h, kn, ks = 20.0, 1.0, 0.5, 1e9, 4e8
    model = incline(psi, b, h)
    probe = Engine(model, _spring_settings(kn, ks, Stage("s", "dynamic", duration_s=0.01)))
    probe.detect()
    limit = probe.stable_time_step()
    stage = Stage("shake", "dynamic", duration_s=0.3, time_step_s=0.9 * limit, history_every=1)
    glued = Coulomb(kn, ks, 40.0, cohesion_pa=1e9, tension_pa=1e9)
    r = run(model, Settings(joints={"default": glued}, stages=(stage,), material=Material(RHO),
                            fixes=(Fix("blocks:0"),)))
    s = r.stages[0]
    assert s.status == "completed" and s.steps > 300
    assert s.slipping_contacts == 0 and s.broken_contacts == 0
    ke = r.history["kinetic_energy_j"]
    weight = RHO * b * h * G
    # static displacement of a point of the block ≤ W/(k b) + rotation W(h/2)/(k b³/4) × b
    static = weight / (min(kn, ks) * b) * (1 + 2 * h / b)
    assert ke.max() <= weight * 2 * static
    half = len(ke) // 2
    assert ke[half:].max() <= 1.5 * ke[:half].max()
    assert s.max_displacement_m <= 2 * static


# --------------------------------------------------------------- 10. in-situ equilibrium --
_ALL_SIDES = ("left", "right", "bottom", "top")
_UNIFORM = InSituStress(sxx_pa=5e6, syy_pa=3e6, sxy_pa=1e6)
_GRAVITY_K0 = InSituStress(sxx_pa=0.5e6, syy_pa=1e6, gravity_gradient=True, k0=0.5)


def _layered(**_):
    """One joint set: every contact is a whole face (no joint crossings)."""
    return build(rect(0.0, 0.0, 4.0, 3.0), [JointSet(30.0, 0.7, origin_xy_m=(0.3, 0.2))])


@pytest.mark.parametrize("builder, insitu, gravity", [
    pytest.param(_layered, _UNIFORM, (0.0, 0.0), id="one-set-uniform"),
    pytest.param(_layered, _GRAVITY_K0, (0.0, -G), id="one-set-gravity-k0"),
    pytest.param(jointed_rectangle, _UNIFORM, (0.0, 0.0), id="two-sets-uniform"),
    pytest.param(jointed_rectangle, _GRAVITY_K0, (0.0, -G), id="two-sets-gravity-k0"),
])
def test_insitu_stress_starts_in_equilibrium(builder, insitu, gravity):
    """Contact forces from σ₀ (F_n = n·σ₀·n l, F_s = t·σ₀·n l) with the same stress as tractions on
    all sides: unbalanced ratio < 1e-5 from the first step (the static stage converges at its first
    check, step 10) and the blocks do not move in a following undamped dynamic stage. The joint
    friction (40°) is well above the stress obliquity on both sets. Where four blocks meet at a
    joint crossing the diagonal blocks touch at a point only: those corner slots carry no stress."""
    model = builder()
    st = Settings(joints={"default": Coulomb(1e10, 5e9, 40.0)}, gravity_m_s2=gravity,
                  stages=(Stage("equilibrium", max_steps=50),
                          Stage("still", "dynamic", duration_s=0.01)),
                  insitu=insitu, material=Material(2700.0),
                  boundary_stress=(BoundaryStress(_ALL_SIDES, from_insitu=True),))
    r = run(model, st)
    eq, still = r.stages
    assert eq.converged and eq.steps == 10
    ratios = r.history["unbalanced_ratio"][1:]
    assert ratios.max() < 1e-5
    # σ/k_n ~ 5e-4 m of joint closure: the blocks stay put to round-off
    assert np.abs(r.displacement_m).max() < 1e-12
    assert np.abs(r.rotation_rad).max() < 1e-12
    assert still.open_contacts == 0
    c = r.contacts
    inner = model.contact_blocks[model.contact_blocks[:, 1] >= 0]
    faces = {(min(i, j), max(i, j)) for i, j in inner.tolist()}
    face = np.array([(a, b) in faces for a, b in zip(c["block_a"].tolist(), c["block_b"].tolist())])
    assert {(a, b) for a, b in zip(c["block_a"][face].tolist(), c["block_b"][face].tolist())} == faces
    assert (c["normal_stress_pa"][face] > 0).all() and not c["slipping"][face].any()
    np.testing.assert_allclose(c["normal_stress_pa"][~face], 0.0, atol=1e-6 * 5e6)
