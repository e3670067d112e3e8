"""Dynamic accuracy of the default time step: an elastic impact keeps its energy within 1 %
(issue 16 item 2; docs/dem.md §2.4).

A rigid block dropped flat from a gap g onto a fixed base, undamped, must rebound to the height it
fell from: in free flight after the impact its energy per unit mass, g_y·u_y + v²/2 (u_y measured
from the release point), is zero if the impact conserved energy. The expected value is exact
mechanics, not a run's output. Several gaps put the instant the contact closes at different
places inside a time step, which is what the error depends on.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from bench_dynamics import impact_error  # noqa: E402  (the drop, measured one way only)


def impact_energy_error(gap_m: float, safety=None) -> float:
    """Energy after the first impact minus energy before, over the energy of the fall m g gap."""
    return impact_error(gap_m, safety)[0]


@pytest.mark.parametrize("gap_mm", [0.8, 0.9, 1.0, 1.1, 1.2])
def test_elastic_impact_keeps_its_energy_within_one_percent_by_default(gap_mm):
    assert abs(impact_energy_error(gap_mm * 1e-3)) < 0.01


def test_impact_error_falls_with_the_step():
    """The error is of order (ωΔt)²: at half the default step it is far smaller than at the
    static stages' 0.5, where it exceeds 1 % for some gap (why dynamic stages use 0.2)."""
    gaps = np.linspace(0.8e-3, 1.2e-3, 5)
    coarse = max(abs(impact_energy_error(g, safety=0.5)) for g in gaps)
    fine = max(abs(impact_energy_error(g, safety=0.1)) for g in gaps)
    assert coarse > 0.01
    assert fine < 0.25 * coarse
