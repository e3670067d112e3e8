"""Shake-table loading (issue 16 items 1 and 3; docs/dem.md §8.2 and §13, problem 16).

Damping that does not eat the input: a block carried by a table moves rigidly with it, so Rayleigh
damping relative to the table must dissipate nothing, while on absolute velocity it dissipates
α m ∫v² dt — a closed form. The Ahola et al. (1996) shake table itself (samples/solve_shaketable.toml)
is checked against the threshold the experiment found: no slip at a table amplitude of 11.7 mm,
slip at 15.5 mm (slow: a few minutes).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rockmass.solver import (Coulomb, Fix, Material, Monitor, Settings, Sine, Stage, TableSine,
                             VelocityInput, run)

from ._models import incline

RHO = 2000.0
SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def _carried_block(reference: str):
    """A 1 m × 0.5 m block on a table (block 0) moved by v = A sin 2πft for two cycles; friction
    far above the table's acceleration, so the block rides with the table."""
    amplitude, f = 0.1, 2.0
    stage = Stage("shake", "dynamic", duration_s=2.0 / f, rayleigh_ratio=0.05,
                  rayleigh_frequency_hz=f, rayleigh_mode="mass", rayleigh_reference=reference)
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 40.0)}, material=Material(RHO),
                        stages=(stage,), fixes=(Fix("blocks:0", "yr"),),
                        velocity_inputs=(VelocityInput("blocks:0", "x",
                                                       Sine(amplitude, f, cycles=2)),),
                        monitors=(Monitor("block", block=1),))
    result = run(incline(0.0), settings)
    alpha = 2 * 0.05 * 2 * math.pi * f  # mass-only Rayleigh: α = 2ξω
    expected = alpha * RHO * 0.5 * amplitude ** 2 * (2.0 / f) / 2  # α m ∫(A sin ωt)² dt
    return result, expected


def test_damping_on_absolute_velocity_takes_alpha_m_integral_v_squared():
    result, expected = _carried_block("absolute")
    energy = result.stages[0].energy
    assert energy["viscous_damping_j"] == pytest.approx(expected, rel=0.02)


def test_damping_relative_to_the_table_leaves_a_carried_block_alone():
    result, expected = _carried_block("inputs")
    energy = result.stages[0].energy
    # what is left damps the block's elastic rocking on its joint, started by the table's jolt
    # (measured 0.6 % of the absolute case)
    assert abs(energy["viscous_damping_j"]) < 0.01 * expected
    # and the block did ride with the table (no slip): same x motion as the table's input
    h = result.history
    assert np.abs(h["block_ux_m"][-1]) < 1e-4


def test_reference_inputs_needs_one_history_per_component():
    stage = Stage("shake", "dynamic", duration_s=0.1, rayleigh_ratio=0.05,
                  rayleigh_frequency_hz=2.0, rayleigh_reference="inputs")
    base = dict(joints={"default": Coulomb(1e9, 1e9, 40.0)}, stages=(stage,))
    with pytest.raises(ValueError, match="needs velocity_inputs"):
        Settings(**base)
    two = (VelocityInput("left", "x", Sine(0.1, 2.0)), VelocityInput("right", "x", Sine(0.2, 2.0)))
    with pytest.raises(ValueError, match="share one history"):
        Settings(**base, velocity_inputs=two)


def test_table_sine_swings_plus_minus_d_and_returns_to_rest():
    """The table's displacement (the integral of the velocity) peaks at ± D and ends at 0."""
    history = TableSine(0.0155, 2.97, cycles=5)
    t = np.linspace(-0.1, 2.0, 400_001)
    v = history(t)
    u = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    assert u.max() == pytest.approx(0.0155, rel=1e-3)
    assert u.min() == pytest.approx(-0.0155, rel=1e-3)
    assert abs(u[-1]) < 1e-9 and v[-1] == 0.0 and v[0] == 0.0
    a = np.gradient(v, t)
    assert np.abs(a).max() == pytest.approx((2 * math.pi * 2.97) ** 2 * 0.0155, rel=0.1)


def test_shaketable_sample_builds_its_settings():
    from rockmass.solve_stage import prepare

    _, model, settings, _, _ = prepare(SAMPLES / "solve_shaketable.toml")
    shaking = settings.stages[-1]
    assert shaking.rayleigh_reference == "inputs"
    assert {type(v.history) for v in settings.velocity_inputs} == {TableSine}
    assert model.n_blocks > 300


@pytest.mark.slow
def test_ahola_shaketable_threshold_between_11p7_and_15p5_mm():
    """Varma et al. (2019) §3: four cycles at each of 3.8, 7.6, 11.7 and 15.5 mm — the blocks
    slipped only at 15.5 mm. The same four cycles each here: the top-left block's displacement
    relative to the table grows by less than 0.1 mm over the 11.7 mm level (settling) and by more
    than three times that over the 15.5 mm level (measured 0.045 and 0.186 mm)."""
    import sys

    sys.path.insert(0, str(SAMPLES.parent / "benchmarks"))
    from bench_shaketable import LEVELS_M, load, shaking

    model, settings = load()
    frequency = next(v.history.frequency_hz for v in settings.velocity_inputs)
    out, _ = shaking(model, settings, LEVELS_M, frequency, 4)
    assert out["status"] == "ok"
    end = {r["level_mm"]: r["slip_mm"] for r in out["rows"] if r["cycle"] == 4}
    grow_11p7 = end[11.7] - end[7.6]
    grow_15p5 = end[15.5] - end[11.7]
    assert grow_11p7 < 0.1
    assert grow_15p5 > 3 * grow_11p7


def _resting_block_stage(mode: str, ratio: float = 0.05, **stage):
    """A 1 m x 0.5 m block resting on a fixed one, one dynamic stage with Rayleigh damping
    ``ratio`` at 2 Hz in ``mode``. Its contact's ω_max is about 2·10³ rad/s, so the stiffness
    term's β = 2ξ/ω (8 ms at 5 %) overdamps it."""
    stage = Stage("rest", "dynamic", duration_s=0.02, rayleigh_ratio=ratio,
                  rayleigh_frequency_hz=2.0, rayleigh_mode=mode, frames=0, **stage)
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 40.0)}, material=Material(RHO),
                        stages=(stage,), fixes=(Fix("blocks:0"),))
    return run(incline(0.0), settings)


def _step_warnings(caught) -> list:
    return [w for w in caught if "stiffness-proportional" in str(w.message)]


def test_a_step_cut_by_stiffness_damping_warns_with_both_steps_and_the_cure():
    with pytest.warns(UserWarning, match='rayleigh_mode = "mass" keeps the step') as caught:
        damped = _resting_block_stage("stiffness")
    warning, = _step_warnings(caught)
    message = str(warning.message)
    without, cut = (float(v) for v in message.split("from ")[1].split(" s (")[0].split(" s to "))
    # the steps named are the run's own: the stiffness run's limit, and the mass-only run's
    undamped = _resting_block_stage("mass")
    assert cut == pytest.approx(damped.stages[0].stable_time_step_s, rel=1e-3)
    assert without == pytest.approx(undamped.stages[0].stable_time_step_s, rel=1e-3)
    # eq. (2.6) with no dashpots: Δt = 4 / (√(4λ + γ²) + γ), λ = (2/Δt₀)², γ = βλ, β = 2ξ/ω
    beta = 2 * 0.05 / (2 * math.pi * 2.0)
    lam = (2.0 / without) ** 2
    assert cut == pytest.approx(4.0 / (math.sqrt(4 * lam + (beta * lam) ** 2) + beta * lam),
                                rel=2e-3)
    assert warning.filename == __file__  # points at the caller of run()


def test_a_small_cut_or_a_given_step_does_not_warn():
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        light = _resting_block_stage("stiffness", ratio=0.001)  # βω_max ≈ 0.4: cut ≈ 1.2x
        given = _resting_block_stage("stiffness", time_step_s=1e-5)
    assert not _step_warnings(caught)
    assert light.status == given.status == "ok"
