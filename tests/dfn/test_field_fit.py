"""Field fitting and the closed loop (rockmass.dfn.field_fit, rockmass.dfn.validation).

Oracles: hand-made face geometry for trace assignment; for the fits, networks generated with known
sets and sampled with virtual scanlines and faces, each recovered parameter compared with the truth
within the tolerance its sampling error gives (validation module docstring), fixed seeds.
"""

import numpy as np
import pytest
from rockmass.dfn import TraceMap
from rockmass.dfn.field_fit import FaceSurvey, assign_traces, fit_field
from rockmass.dfn.generation import (
    FisherOrientation,
    FractureSetSpec,
    IntensityP32,
    generate,
)
from rockmass.dfn.orientation import normal_from_dip
from rockmass.dfn.sizes import PowerLawSize
from rockmass.dfn.validation import (
    POLE_TOLERANCE_FACTOR,
    closed_loop,
    virtual_face,
    virtual_scanline,
)

L = 40.0
C = L / 2
SIZE = PowerLawSize(1.0, 20.0, 2.5)
SPECS = [FractureSetSpec(FisherOrientation(50, 270, 20), SIZE, IntensityP32(1.0), name="J1"),
         FractureSetSpec(FisherOrientation(80, 10, 20), SIZE, IntensityP32(1.0), name="J2"),
         FractureSetSpec(FisherOrientation(70, 150, 20), SIZE, IntensityP32(1.0), name="J3")]
LINES = [([2, C, C], [L - 2, C, C]), ([C, 2, C], [C, L - 2, C]), ([C, C, 2], [C, C, L - 2])]
WINDOW = [(-15, -15), (15, -15), (15, 15), (-15, 15)]
FACES = [([C, C, C], [1, 0, 0], WINDOW), ([C, C, C], [0, 1, 0], WINDOW), ([C, C, C], [0, 0, 1], WINDOW)]


def test_vertical_face_frame_puts_horizontal_planes_along_u():
    tm = TraceMap.from_polylines([[(0, 0), (1, 0.05)], [(0, 0), (0.05, 1)], [(0, 0), (-1, 0)]],
                                 window=[(-2, -2), (2, -2), (2, 2), (-2, 2)])
    face = FaceSurvey.from_dip(tm, 90.0, 0.0)                      # vertical face looking North
    np.testing.assert_allclose(face.normal, [0, 1, 0], atol=1e-12)
    poles = [[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]]                  # horizontal plane; N-S striking vertical plane
    assert assign_traces(face, poles).tolist() == [0, 1, 0]


def test_p21_sd_is_poisson_count_times_length_scatter_by_hand():
    from rockmass.dfn.field_fit import _trace_sample

    t = _trace_sample(np.array([1.0, 3.0, 0.0]), 4.0)          # the zero-length trace is not counted
    assert (t.m, t.p21, t.mean_m) == (2, 1.0, 2.0)
    assert t.p21_sd == pytest.approx(np.sqrt((1 + 2.0 / 4.0) / 2))  # var 2 (ddof 1), CV² = 1/2
    assert t.mean_sd == pytest.approx(1.0)
    assert _trace_sample(np.array([2.0]), 4.0).p21_sd is None     # one trace: no spread to measure


def test_virtual_scanline_reports_the_dip_of_each_disk_hit():
    net = generate(SPECS[:1], [0, 0, 0, 20, 20, 20], seed=3)
    survey = virtual_scanline(net, [10, 10, 0.5], [10, 10, 19.5])
    hits = survey.poles()
    assert survey.n_intersections >= 3
    assert survey.plunge_deg == -90.0 and survey.length_m == pytest.approx(19.0)
    # every reported pole is the (axial) normal of a disk of the network
    cos = np.abs(hits @ net.normal.T).max(axis=1)
    np.testing.assert_allclose(cos, 1.0, atol=1e-9)


def test_fit_field_needs_a_scanline_and_names_what_is_missing():
    with pytest.raises(ValueError, match="scanline"):
        fit_field([], [])
    tm = TraceMap.from_polylines([[(0, 0), (1, 0)]])
    with pytest.raises(ValueError, match="window"):
        FaceSurvey(tm, normal_from_dip(90, 0))
    with pytest.raises(ValueError, match="size_family"):
        net = generate(SPECS[:1], [0, 0, 0, 20, 20, 20], seed=3)
        fit_field([virtual_scanline(net, [10, 10, 0.5], [10, 10, 19.5])], size_family="gamma")


@pytest.fixture(scope="module")
def loops():
    # two fixed seeds: ~19,000 disks each, ~160 scanline hits and ~2,000 face traces
    return [closed_loop(SPECS, [0, 0, 0, L, L, L], scanlines=LINES, faces=FACES, seed=s) for s in (1, 2)]


def test_closed_loop_recovers_every_parameter_within_its_sampling_error(loops):
    rows = [r for loop in loops for r in loop.rows]
    assert len(rows) == 2 * 3 * 5                     # pole, kappa, p32, alpha, r_min for 3 sets, 2 seeds
    assert all(np.isfinite(r["tolerance"]) for r in rows)
    # each row is a ~3σ (99.7 %) test: over 30 rows at most one miss is expected by chance, and no
    # row may miss by more than 4/3 of its tolerance (4σ)
    misses = [r for r in rows if not r["ok"]]
    assert len(misses) <= 1, misses
    assert all(abs(r["error"]) <= 4 / 3 * r["tolerance"] for r in rows)


def test_closed_loop_recovers_power_law_exponent_kappa_and_p32(loops):
    for loop in loops:
        by = {(r["set"], r["quantity"]): r for r in loop.rows}
        fitted = {s.name: s for s in loop.fit.sets}
        assert len(fitted) == 3
        for spec in SPECS:
            alpha = by[(spec.name, "size.alpha")]
            assert abs(alpha["error"]) <= 3 * alpha["sd"]
            pole = by[(spec.name, "mean_pole_deg")]
            assert pole["recovered"] <= pole["tolerance"]
            assert pole["tolerance"] > 0 and POLE_TOLERANCE_FACTOR == pytest.approx(1.52, abs=0.01)
            p32 = by[(spec.name, "p32")]
            assert abs(p32["error"]) <= 3 * p32["sd"]


def test_loop_report_is_json_ready(loops):
    import json

    text = json.dumps(loops[0].as_dict(), allow_nan=False)
    assert '"rows"' in text


def test_fitted_specs_generate_a_network_near_the_fitted_p32(loops):
    fit = loops[0].fit
    specs = fit.specs()
    net = generate(specs, [0, 0, 0, 30, 30, 30], seed=9)
    for j, s in enumerate(fit.sets):
        assert net.p32(j) == pytest.approx(s.p32, rel=0.05)


def test_face_without_traces_of_a_set_still_gives_its_p32():
    net = generate(SPECS[:1], [0, 0, 0, L, L, L], seed=4)
    face = virtual_face(net, [C, C, C], [0, 0, 1], WINDOW)
    scan = virtual_scanline(net, [2, C, C], [L - 2, C, C])
    fit = fit_field([scan], [face], n_sets=1, size_family="power_law", r_max_m=20.0)
    s = fit.sets[0]
    assert s.p32 > 0 and np.isfinite(s.p32_sd) and s.n_observations == 2
    assert abs(s.p32 - net.p32(0)) <= 3 * s.p32_sd


def test_bootstrap_specs_generate_only_the_measured_poles_of_each_set(loops):
    fit = loops[0].fit
    specs = fit.specs(orientation="bootstrap")
    net = generate(specs, [0, 0, 0, 15, 15, 15], seed=5)
    for j, s in enumerate(fit.sets):
        normals = net.normal[net.set_id == j]
        assert normals.shape[0] > 10
        # every generated normal is (up to sign) one of the set's measured poles
        assert np.allclose(np.abs(normals @ s.poles.T).max(axis=1), 1.0, atol=1e-12)
    assert sum(s.poles.shape[0] for s in fit.sets) == loops[0].n_hits
    with pytest.raises(ValueError, match="orientation"):
        fit.sets[0].spec(orientation="kent")
