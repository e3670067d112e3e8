"""Quiet boundaries whose impedance comes from the rock mass (docs/dem.md §14.1; issue 16 item 5).

A column of rigid blocks of height s on joints k_n, k_s is a mass-spring chain whose long waves
travel at √(k s/ρ): its impedance is √(ρ k_n s) (P) and √(ρ k_s s) (S), not that of the intact
rock. The default rule (``impedance = "rock_mass"``) must give exactly these from the joint
stiffness and the block size, and a Ricker pulse then leaves through the boundary with < 2 % of
its energy reflected. The answers: the closed-form impedances, the reflection of the discrete chain
(:func:`tests.solver._models_advanced.chain_reflection`, leap-frog Δt included) weighted by the
incident spectrum, and its long-wave limit ((Z_q − Z)/(Z_q + Z))² for a mismatched dashpot.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from pydantic import ValidationError

from rockmass.solver import (BoundaryStress, Coulomb, Fix, FreeField, InSituStress, Material,
                             Monitor, QuietBoundary, Ricker, Settings, Stage, VelocityInput, run)
from rockmass.solver.engine import Engine
from rockmass.solver.loading import apply_insitu, joint_compliance, quiet_edge_table

from ._models import hand_model, rect
from ._models_advanced import chain_column, chain_reflection

RHO, KN, KS, S = 2600.0, 2e10, 1e10, 0.5          # density, joint stiffnesses (Pa/m), block height
K_ROCK, G_ROCK = 30e9, 20e9                        # intact moduli (M = 56.7 GPa: 5.7 × k_n s)
SIG0 = 2e6                                         # preload keeping the joints closed and stuck


def _settings(n, impedance="rock_mass", component="y", duration=0.01, monitor=None, freq=150.0,
              moduli=(K_ROCK, G_ROCK)):
    """A column of ``n`` blocks (:func:`chain_column`) preloaded by σ₀, moving only along
    ``component`` (the other translation and the rotation fixed), a quiet base, and the top block
    driven by a Ricker velocity pulse of peak frequency ``freq``."""
    return Settings(
        joints={"default": Coulomb(KN, KS, 40.0)}, material=Material(RHO, *moduli),
        gravity_m_s2=(0.0, 0.0), insitu=InSituStress(syy_pa=SIG0),
        boundary_stress=(BoundaryStress(("bottom",), syy_pa=SIG0),),
        quiet=QuietBoundary(("bottom",), impedance=impedance),
        fixes=(Fix(f"blocks:{','.join(map(str, range(n)))}", "xr" if component == "y" else "yr"),),
        velocity_inputs=(VelocityInput("top", component, Ricker(
            -0.01 if component == "y" else 0.01, freq)),),
        time_step_safety=0.5,
        stages=(Stage("wave", "dynamic", duration_s=duration, history_every=1, frames=0),),
        monitors=() if monitor is None else (Monitor("m", block=monitor),))


def _quiet_table(model, settings):
    eng = Engine(model, settings)
    eng.detect()
    apply_insitu(eng, settings.insitu)
    return quiet_edge_table(eng, settings.quiet)


@pytest.mark.parametrize("s", [0.5, 0.25])
def test_rock_mass_impedance_is_that_of_the_joint_chain(s):
    """Default rule on the base of a column of blocks of height s: ρC_p = √(ρ k_n s),
    ρC_s = √(ρ k_s s) (the joints parallel to the boundary, spacing s; the base edge counts as the
    joint the column would continue with). The other rules: in series with the intact rock,
    1/M = 1/(K + 4G/3) + 1/(k_n s); the intact rock alone; explicit wave speeds."""
    model = chain_column(10, s, 1.0)
    table = _quiet_table(model, _settings(10))
    assert len(table) == 1 and table[0, 0] == 0  # the base edge of block 0
    np.testing.assert_allclose(table[0, 6:8], [math.sqrt(RHO * KN * s), math.sqrt(RHO * KS * s)],
                               rtol=1e-12)
    m_rock = K_ROCK + 4 * G_ROCK / 3
    series = _quiet_table(model, _settings(10, "rock_mass_intact"))[0, 6:8]
    np.testing.assert_allclose(series, [math.sqrt(RHO / (1 / m_rock + 1 / (KN * s))),
                                        math.sqrt(RHO / (1 / G_ROCK + 1 / (KS * s)))], rtol=1e-12)
    rock = _quiet_table(model, _settings(10, "rock"))[0, 6:8]
    np.testing.assert_allclose(rock, [math.sqrt(RHO * m_rock), math.sqrt(RHO * G_ROCK)], rtol=1e-12)
    given = dataclasses.replace(_settings(10),
                                quiet=QuietBoundary(("bottom",), p_wave_speed_m_s=3000.0))
    np.testing.assert_allclose(_quiet_table(model, given)[0, 6:8],
                               [RHO * 3000.0, math.sqrt(RHO * KS * s)], rtol=1e-12)


def test_joint_compliance_of_two_sets():
    """Equivalent continuum of a brick of w × h between joints on all four faces (each face shared
    by two blocks): along y, 1/M = 1/(k_n h); in shear both sets slide, 1/G = 1/(k_s h) + 1/(k_s w)
    (a face at 45° to the direction: c² = s² = ½, 1/M = (1/4)(1/k_n + 1/k_s) per unit joint area
    per unit volume)."""
    w, h = 2.0, 0.5
    faces = np.array([[w, 0.0, 1.0, KN, KS], [w, 0.0, -1.0, KN, KS],
                      [h, 1.0, 0.0, KN, KS], [h, -1.0, 0.0, KN, KS]])
    inv_m, inv_g = joint_compliance(faces, w * h, (0.0, 1.0))
    assert inv_m == pytest.approx(1 / (KN * h), rel=1e-12)
    assert inv_g == pytest.approx(1 / (KS * h) + 1 / (KS * w), rel=1e-12)
    one = np.array([[2.0, 1.0, 0.0, KN, KS]])  # joint area per volume 2/(2·1) = 1
    d = (math.sqrt(0.5), math.sqrt(0.5))
    assert joint_compliance(one, 1.0, d)[0] == pytest.approx(0.25 * (1 / KN + 1 / KS), rel=1e-12)


def _pulse_reflection(component, impedance):
    """(reflected energy at a monitor 60 blocks above the base, the chain's prediction, the ledger's
    (work in − absorbed)/work in, Z_q / Z). Energy flux ∝ Z v², the same site both ways, so the
    reflected fraction is Σv²(reflected)/Σv²(incident), split when the incident pulse has passed the
    monitor and its reflection has not arrived."""
    n, mon, freq = 160, 60, 150.0
    k = KN if component == "y" else KS
    c = math.sqrt(k * S / RHO)
    t_arrive = (n - 1 - mon) * S / c
    duration = t_arrive + 2 * mon * S / c + 3.5 / freq  # the reflection has passed the monitor
    settings = _settings(n, impedance, component, duration, mon, freq)
    table = _quiet_table(chain_column(n, S, 1.0), settings)
    z_q = table[0, 6 if component == "y" else 7]
    result = run(chain_column(n, S, 1.0), settings)
    assert result.status == "ok", result.diagnostic
    stage = result.stages[0]
    h = result.history
    v = h[f"m_v{component}_m_s"]
    t_split = t_arrive + 0.5 * (3.0 / freq + 2 * mon * S / c)
    incident = np.where(h["time_s"] < t_split, v, 0.0)
    reflected = np.where(h["time_s"] >= t_split, v, 0.0)
    measured = (reflected ** 2).sum() / (incident ** 2).sum()
    nfft = 1 << 16
    spec = np.fft.rfft(incident, nfft)[1:]
    omega = 2 * np.pi * np.fft.rfftfreq(nfft, stage.time_step_s)[1:]
    r_chain = chain_reflection(omega, k * 1.0, RHO * S * 1.0, z_q * 1.0, stage.time_step_s)
    predicted = (np.abs(r_chain) ** 2 * np.abs(spec) ** 2).sum() / (np.abs(spec) ** 2).sum()
    e = stage.energy
    ledger = (e["work_boundary_j"] - e["quiet_boundary_j"]) / e["work_boundary_j"]
    return measured, predicted, ledger, z_q / math.sqrt(RHO * k * S)


@pytest.mark.parametrize("component", ["y", "x"])
def test_ricker_pulse_leaves_through_a_rock_mass_quiet_boundary(component):
    """A Ricker pulse (150 Hz: 13 blocks per wavelength in shear, 18 in compression) through 160
    blocks of 0.5 m leaves through a base whose impedance the default rule set from k_n, k_s and
    the block size (intact moduli given, and 5.7 × stiffer than the joint chain): reflected energy
    < 2 % at a monitor (measured 0.17 % P, 0.35 % S: the chain's discreteness, |R| ≈ θ/4), within
    2 % + 1e-5 of the discrete chain's prediction, and the ledger agrees — the energy the driven top
    put in less what the base absorbed is what remains, the reflection (within 2e-3; measured
    0.171 % P, 0.348 % S)."""
    measured, predicted, ledger, ratio = _pulse_reflection(component, "rock_mass")
    print(f"rock_mass {component}: reflected {measured:.4%} (chain {predicted:.4%}, ledger "
          f"{ledger:.4%})")
    assert ratio == pytest.approx(1.0, rel=1e-12)
    assert measured < 0.02
    assert abs(measured - predicted) < 0.02 * predicted + 1e-5
    assert abs(ledger - measured) < 2e-3


def test_intact_moduli_reflect_as_the_impedance_mismatch_says():
    """The issue's 17 %: a base given the intact rock's moduli (ρC_p = √(ρ(K + 4G/3)), 2.4 × the
    chain's) reflects ((Z_q − Z)/(Z_q + Z))² of a long wave; the discrete chain's prediction for
    this pulse within 2 % (measured 17.0 %)."""
    measured, predicted, _, ratio = _pulse_reflection("y", "rock")
    print(f"rock y: reflected {measured:.4%} (chain {predicted:.4%})")
    long_wave = ((ratio - 1) / (ratio + 1)) ** 2
    assert abs(measured - predicted) < 0.02 * predicted
    assert measured > 0.9 * long_wave > 0.1


def test_rock_mass_without_a_crossing_joint_needs_moduli():
    """A single block has no joint: the rock mass is the intact rock (its moduli, when given: the
    same dashpots as ``impedance = "rock"``), and without moduli a clear error naming the block."""
    model = hand_model([rect(0.0, 0.0, 1.0, 1.0)], [])
    base = dict(joints={"default": Coulomb(KN, KS, 30.0)}, gravity_m_s2=(0.0, 0.0),
                stages=(Stage("d", "dynamic", duration_s=1e-3),))
    with_moduli = Settings(**base, material=Material(RHO, K_ROCK, G_ROCK),
                           quiet=QuietBoundary(("bottom",)))
    rock = Settings(**base, material=Material(RHO, K_ROCK, G_ROCK),
                    quiet=QuietBoundary(("bottom",), impedance="rock"))
    np.testing.assert_array_equal(_quiet_table(model, with_moduli), _quiet_table(model, rock))
    without = Settings(**base, material=Material(RHO), quiet=QuietBoundary(("bottom",)))
    with pytest.raises(ValueError, match="no joint of block 0 crosses"):
        run(model, without)


def test_impedance_rules_are_checked_with_the_settings():
    """``rock`` and ``rock_mass_intact`` need the intact moduli (or both wave speeds); a side
    cannot be quiet and free-field at once."""
    base = dict(joints={"default": Coulomb(KN, KS, 30.0)}, stages=(Stage("s"),))
    Settings(**base, quiet=QuietBoundary(("bottom",)))  # rock_mass: joints only
    Settings(**base, quiet=QuietBoundary(("bottom",), "rock", 3000.0, 1800.0))
    for rule in ("rock", "rock_mass_intact"):
        with pytest.raises(ValidationError, match="needs material.bulk_modulus_pa"):
            Settings(**base, quiet=QuietBoundary(("bottom",), rule))
    with pytest.raises(ValidationError, match="also quiet sides"):
        Settings(**base, quiet=QuietBoundary(("bottom", "left")),
                 free_field=FreeField(("left", "right")))
