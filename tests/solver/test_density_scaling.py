"""Density scaling of rigid blocks in static stages (``Settings.density_scaling``, docs/dem.md
§10.4): the same equilibrium, to the tolerance, in far fewer steps when thin blocks set the step;
gravity keeps the true weights; the ledger books the kinetic energy the scaled masses carry."""

from dataclasses import replace

import numpy as np
import pytest
from pydantic import TypeAdapter

from rockmass.solver import Coulomb, Fix, Material, Settings, Sine, Stage, VelocityInput, run

from ._models import hand_model, rect

RHO, G, KN, WIDTH = 2500.0, 9.81, 1e9, 1.0
HEIGHTS = (1.0, 0.02, 1.0, 0.05, 1.0, 0.01, 1.0)  # slivers between 1 m blocks


def _column():
    """A fixed base block, then the HEIGHTS stacked on it, joints between neighbours."""
    tops = np.cumsum((0.0,) + HEIGHTS)
    blocks = [rect(0, -1, WIDTH, 0)] + [rect(0, y0, WIDTH, y1) for y0, y1 in zip(tops, tops[1:])]
    return hand_model(blocks, pairs=[(i, i + 1) for i in range(len(HEIGHTS))]), tops


def _settings(scaled, **kw):
    return Settings(joints={"default": Coulomb(KN, KN, 40.0)},
                    stages=(Stage("gravity", tolerance=1e-7),), material=Material(RHO),
                    fixes=(Fix("blocks:0"), Fix("left", dofs="x"), Fix("right", dofs="x")),
                    density_scaling=scaled, **kw)


def test_a_column_with_slivers_settles_to_the_closed_form_in_fewer_steps():
    """Joint j (under block j+1) closes by the weight above it over k_n·b: block k settles by the
    sum of the closures below it. Scaled and unscaled both reach it (relative 1e-5); the scaled
    run needs at most a third of the steps, its step set by the 1 m blocks, not the slivers."""
    model, tops = _column()
    weights = RHO * G * WIDTH * np.asarray(HEIGHTS)
    above = np.cumsum(weights[::-1])[::-1]  # weight on joint j (under block j + 1)
    expected = -np.concatenate([[0.0], np.cumsum(above / (KN * WIDTH))])
    plain, scaled = run(model, _settings(False)), run(model, _settings(True))
    for r in (plain, scaled):
        assert r.stages[0].converged
        np.testing.assert_allclose(r.displacement_m[:, 1], expected, rtol=1e-5, atol=1e-12)
    assert scaled.stages[0].steps <= plain.stages[0].steps / 3
    assert scaled.stages[0].time_step_s >= 3 * plain.stages[0].time_step_s
    ledger = scaled.stages[0].energy
    assert abs(ledger.residual_j) < 1e-3 * ledger.work_gravity_j


def test_density_scaling_leaves_a_dynamic_stage_alone():
    """A dynamic stage after a scaled static one steps with the true masses: the same step as
    without scaling (the static stage's is longer)."""
    model, _tops = _column()
    shake = (VelocityInput("bottom", "x", Sine(0.01, 5.0, cycles=1)),)
    stages = (Stage("gravity", tolerance=1e-7), Stage("shake", "dynamic", duration_s=0.05,
                                                       frames=0))
    plain, scaled = (run(model, replace(_settings(on), stages=stages, velocity_inputs=shake))
                     for on in (False, True))
    assert scaled.stages[1].time_step_s == pytest.approx(plain.stages[1].time_step_s, rel=1e-9)
    assert scaled.stages[0].time_step_s > 3 * plain.stages[0].time_step_s


def test_density_scaling_is_left_out_of_dumps_when_off():
    """Adding the setting changed no existing config hash: off, it is not dumped."""
    dump = TypeAdapter(Settings).dump_python
    assert "density_scaling" not in dump(_settings(False), mode="json")
    assert dump(_settings(True), mode="json")["density_scaling"] is True
