"""Zones per wavelength in dynamic stages (docs/dem.md §16.9): the inputs' highest frequency read
off their spectra, against closed forms, and the warning for zones too coarse for it."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from rockmass.solver import Coulomb, Material, Settings, Sine, Stage, VelocityInput
from rockmass.solver.deformable import zone_model
from rockmass.solver.settings import Deformable, Ricker, TableHistory
from rockmass.solver.wavelength import (ENERGY_FRACTION, highest_frequency_hz, wave_checks,
                                        warn_coarse_zones)
from rockmass.solver.zones import Elastic

from ._models import hand_model, rect

RHO, KB, GB = 2500.0, 2e9, 1.2e9


def test_a_sine_has_its_own_frequency():
    assert highest_frequency_hz(Sine(0.1, 10.0, cycles=3), 2.0) == 10.0


def _ricker_cutoff(peak_frequency_hz):
    """A Ricker wavelet's Fourier amplitude is ∝ x² exp(−x²), x = f/f_p: the frequency below which
    99 % of its energy (∝ x⁴ exp(−2x²)) lies, integrated with quad."""
    power = lambda x: x ** 4 * math.exp(-2 * x * x)  # noqa: E731
    total = quad(power, 0, math.inf)[0]
    x99 = brentq(lambda x: quad(power, 0, x)[0] - ENERGY_FRACTION * total, 0.5, 5.0)
    return x99 * peak_frequency_hz


def test_a_ricker_wavelets_cutoff_matches_its_spectrum():
    assert highest_frequency_hz(Ricker(0.2, 25.0), 0.4) == pytest.approx(_ricker_cutoff(25.0),
                                                                        rel=0.01)


def test_a_recorded_ricker_wavelet_has_the_same_cutoff():
    """A TableHistory of a 10 Hz Ricker wavelet sampled at 1 kHz (a record): the same cutoff."""
    t = np.arange(0.0, 1.0, 1e-3)
    record = TableHistory(tuple(t), tuple(Ricker(0.2, 10.0)(t)))
    assert highest_frequency_hz(record, 1.5) == pytest.approx(_ricker_cutoff(10.0), rel=0.01)


def test_a_constant_history_carries_no_wave():
    assert highest_frequency_hz(lambda t: np.full_like(t, 0.3), 1.0) is None


def _settings(frequency_hz, zone_size_m):
    return Settings(joints={"default": Coulomb(1e9, 1e9, 30.0)},
                    stages=(Stage("rest"), Stage("shake", "dynamic", duration_s=1.0)),
                    material=Material(RHO),
                    velocity_inputs=(VelocityInput("bottom", "x", Sine(0.01, frequency_hz)),),
                    deformable=(Deformable("blocks:0", Elastic(KB, GB), zone_size_m),))


def _longest_edge(zoned):
    longest = 0.0
    for a, b, c in zoned.tri:
        for p, q in ((a, b), (b, c), (c, a)):
            longest = max(longest, float(np.hypot(*(zoned.nodes[p] - zoned.nodes[q]))))
    return longest


@pytest.mark.parametrize("frequency_hz, coarse", [(20.0, False), (2000.0, True)])
def test_zones_per_wavelength_and_the_warning_for_coarse_zones(frequency_hz, coarse):
    """One row for the dynamic stage: λ = √(G/ρ)/f over the longest zone edge; a warning naming
    the zone size that would do when fewer than 10 zones span it, none otherwise."""
    settings = _settings(frequency_hz, 0.1)
    zoned = zone_model(hand_model([rect(0, 0, 1, 0.5)], pairs=[]), settings)
    rows = wave_checks(zoned, settings)
    assert [r["stage"] for r in rows] == ["shake"]
    c_s = math.sqrt(GB / RHO)
    h = _longest_edge(zoned)
    assert rows[0]["zone_size_m"] == pytest.approx(h, rel=1e-12)
    assert rows[0]["zones_per_wavelength"] == pytest.approx(c_s / frequency_hz / h, rel=1e-9)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_coarse_zones(rows)
    assert bool(caught) == coarse
    if coarse:
        assert f"zone_size_m <= {c_s / frequency_hz / 10:.3g} m" in str(caught[0].message)
