"""The report's figures drawn from stage summaries (issue 19, item 5), each against an answer worked
out independently: barycentric coordinates by hand, trace lengths by shapely, the density's integral
over the hemisphere, the fitted laws' closed forms, the contact table's own numbers.

The figures are matplotlib ``Figure`` objects (Agg, no pyplot state); the tests read the artists'
data back rather than the pixels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rockmass.blockgen.plots import contact_segments, draw_contact_values
from rockmass.dfn import TraceMap, trace_map_statistics
from rockmass.dfn.fisher import fisher_density, sample_fisher
from rockmass.dfn.intensity import clipped_lengths_m
from rockmass.dfn.plots import (CB_LINES, connections_per_branch_line, plot_p21_map, plot_rqd, plot_spacings,
                                plot_trace_lengths, plot_xyi_ternary, ternary_xy)
from rockmass.dfn.scanline import Scanline
from rockmass.dfn.scanline_stats import scanline_statistics
from rockmass.dfn.stereonet import (equal_area_vectors, equal_area_xy, kamb_kappa, plot_pole_density,
                                    pole_density)
from rockmass.dfn.trace_stats import p21_map

SQRT3_2 = math.sqrt(3.0) / 2.0


def _scatter_points(ax) -> list[np.ndarray]:
    return [np.asarray(c.get_offsets()) for c in ax.collections if hasattr(c, "get_offsets")]


# ------------------------------------------------------------------------------- XYI ternary --


def test_ternary_point_of_hand_counted_nodes_is_barycentric():
    # I 6, Y 3, X 1: proportions 0.6, 0.3, 0.1 -> x = pX + pI/2 = 0.4, y = (√3/2) pI
    assert ternary_xy(6, 3, 1) == pytest.approx([0.4, 0.6 * SQRT3_2], abs=1e-12)
    assert ternary_xy(5, 0, 0) == pytest.approx([0.5, SQRT3_2])   # all I: the top corner
    assert ternary_xy(0, 7, 0) == pytest.approx([0.0, 0.0])       # all Y: bottom left
    assert ternary_xy(0, 0, 2) == pytest.approx([1.0, 0.0])       # all X: bottom right


def test_ternary_figure_puts_the_network_at_its_barycentric_point():
    fig = plot_xyi_ternary(6, 3, 1)
    points = [p for p in _scatter_points(fig.axes[0]) if p.shape == (1, 2)]
    assert len(points) == 1
    assert points[0][0] == pytest.approx([0.4, 0.6 * SQRT3_2], abs=1e-12)


@pytest.mark.parametrize("c_b", CB_LINES)
def test_reference_lines_have_constant_connections_per_branch(c_b):
    ends = connections_per_branch_line(c_b)
    for t in (0.0, 0.3, 1.0):                       # points along the drawn line
        x, y = (1 - t) * ends[0] + t * ends[1]
        p_i = y / SQRT3_2                           # invert x = pX + pI/2, y = (√3/2) pI
        p_x = x - p_i / 2
        p_y = 1 - p_i - p_x
        n_b = (p_i + 3 * p_y + 4 * p_x) / 2         # Sanderson & Nixon (2015): N_B and C_B
        assert (3 * p_y + 4 * p_x) / n_b == pytest.approx(c_b, abs=1e-12)


def test_ternary_refuses_a_network_without_nodes():
    with pytest.raises(ValueError, match="not all zero"):
        ternary_xy(0, 0, 0)


# ---------------------------------------------------------------------------------- P21 map --


def _random_map(seed: int) -> tuple[TraceMap, list]:
    rng = np.random.default_rng(seed)  # seed fixed: a reproducible map of 60 traces
    starts = rng.uniform(-2.0, 12.0, size=(60, 2))
    ends = starts + rng.normal(0.0, 3.0, size=(60, 2))
    segments = np.hstack([starts, ends]).tolist()
    segments.append([0.0, 5.0, 10.0, 5.0])            # along a grid line (cells of 1 m)
    segments.append([3.0, 0.0, 3.0, 10.0])            # and along another
    window = [(0.0, 0.0), (10.0, 0.0), (10.0, 7.0), (6.0, 10.0), (0.0, 10.0)]  # not a rectangle
    return TraceMap.from_segments(segments, window=window), window


def test_p21_map_cells_add_up_to_the_total_trace_length_in_the_window():
    traces, window = _random_map(seed=3)
    grid = p21_map(traces, window, cells=10)
    total = float(clipped_lengths_m(traces, window).sum())   # shapely's clipped lengths
    assert grid.length.sum() == pytest.approx(total, abs=1e-9)
    assert grid.area.sum() == pytest.approx(shapely.Polygon(window).area, abs=1e-9)
    assert grid.length.shape == grid.area.shape == (10, 10)


def test_a_trace_along_a_grid_line_is_counted_once():
    traces = TraceMap.from_segments([[0.0, 5.0, 10.0, 5.0]], window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    grid = p21_map(traces, traces.window_xy_m, cells=10)
    assert grid.length.sum() == pytest.approx(10.0, abs=1e-12)
    assert grid.length[5] == pytest.approx(np.ones(10), abs=1e-12)  # the cells above it (half-open)
    assert grid.length[4] == pytest.approx(np.zeros(10), abs=0)      # and none below
    assert grid.p21[5] == pytest.approx(np.ones(10))  # 1 m of trace in 1 m²


def test_p21_map_in_the_summary_matches_the_map_p21():
    traces, window = _random_map(seed=5)
    stats = trace_map_statistics(traces, window=window)
    doc = stats.to_dict()["P21 Map"]
    length, area = np.array(doc["length"]), np.array(doc["area"])
    assert length.sum() / area.sum() == pytest.approx(stats.intensity.p21.value, rel=1e-9)
    assert doc["shape"] == list(length.shape)
    fig = plot_p21_map(doc["p21"], doc["origin_xy"], doc["cell_size"])
    mesh = fig.axes[0].collections[0]
    shown = np.ma.masked_invalid(np.array([[np.nan if v is None else v for v in r] for r in doc["p21"]]))
    assert np.ma.allequal(mesh.get_array().reshape(shown.shape), shown)


def test_p21_map_does_not_modify_the_trace_map():
    traces, window = _random_map(seed=3)
    before = traces.xy_m.copy(), traces.offsets.copy(), traces.window_xy_m.copy()
    p21_map(traces, window)
    after = traces.xy_m, traces.offsets, traces.window_xy_m
    assert all(np.array_equal(a, b) for a, b in zip(before, after))


# ---------------------------------------------------------------------------- trace lengths --


def test_trace_length_ccdf_is_rank_over_count_with_censored_traces_open():
    lengths = [4.0, 1.0, 2.0, 8.0, 0.0]             # the zero length is left out
    censored = [False, True, False, True, False]
    fig = plot_trace_lengths(lengths, censored, fitted_survival=lambda l: np.exp(-l / 3.0))
    ax = fig.axes[0]
    complete, cut = _scatter_points(ax)[:2]
    # sorted longest first: 8 (1/4), 4 (2/4), 2 (3/4), 1 (4/4)
    assert complete.tolist() == [[4.0, 0.5], [2.0, 0.75]]
    assert cut.tolist() == [[8.0, 0.25], [1.0, 1.0]]
    line = ax.lines[0]
    assert line.get_ydata() == pytest.approx(np.exp(-np.asarray(line.get_xdata()) / 3.0))
    assert line.get_xdata()[0] == pytest.approx(1.0) and line.get_xdata()[-1] == pytest.approx(8.0)


def test_trace_length_plot_of_no_trace_is_empty_not_an_error():
    fig = plot_trace_lengths([], [], fitted_survival=lambda l: l)
    assert not fig.axes[0].lines


# ----------------------------------------------------------------------------- pole density --


def _cluster(n=40, kappa=30.0, seed=2):
    rng = np.random.default_rng(seed)  # seed fixed: one reproducible Fisher cluster
    mean = np.array([0.3, -0.4, -0.866])
    mean /= np.linalg.norm(mean)
    return sample_fisher(rng, mean, kappa, n), mean


def test_pole_density_integrates_to_the_number_of_poles():
    poles, _ = _cluster()
    g = np.linspace(-1.0, 1.0, 801)
    step = g[1] - g[0]
    xy = np.stack(np.meshgrid(g, g), axis=-1)
    d = pole_density(poles, equal_area_vectors(xy))
    # the equal-area net maps the hemisphere's 2π sr onto the unit disk's area π: dΩ = 2 dX dY
    integral = 2.0 * np.nansum(d) * step * step
    assert integral == pytest.approx(poles.shape[0], rel=5e-3)


def test_pole_density_of_one_pole_is_the_axial_fisher_density():
    pole = np.array([0.0, 0.6, -0.8])
    x = np.array([[0.1, 0.5, -0.86], [0.7, 0.0, -0.71], [1.0, 0.0, 0.0]])
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    expected = fisher_density(x, pole, 5.0) + fisher_density(-x, pole, 5.0)
    assert pole_density([pole], x, kappa=5.0) == pytest.approx(expected, rel=1e-12)


def test_pole_density_peaks_at_the_mean_pole_of_a_symmetric_cluster():
    mean = np.array([0.0, 0.0, -1.0])
    ring = [[0.2 * math.cos(a), 0.2 * math.sin(a), -1.0] for a in np.linspace(0, 2 * math.pi, 6, endpoint=False)]
    poles = np.vstack([mean, np.array(ring) / np.linalg.norm(ring, axis=1, keepdims=True)])
    g = np.linspace(-1.0, 1.0, 201)
    xy = np.stack(np.meshgrid(g, g), axis=-1)
    d = pole_density(poles, equal_area_vectors(xy))
    peak = np.unravel_index(np.nanargmax(d), d.shape)
    assert xy[peak] == pytest.approx(equal_area_xy(mean), abs=g[1] - g[0])


def test_pole_density_is_the_same_in_chunks(monkeypatch):
    from rockmass.dfn import stereonet

    poles, mean = _cluster(n=50)
    x = np.vstack([mean, [[1.0, 0.0, 0.0]], [[np.nan] * 3]])
    whole = pole_density(poles, x)
    monkeypatch.setattr(stereonet, "_DENSITY_CHUNK", 7)   # 2 poles per pass
    chunked = pole_density(poles, x)
    assert chunked[:2] == pytest.approx(whole[:2], rel=1e-12) and np.isnan(chunked[2])


def test_equal_area_vectors_invert_the_projection():
    poles, _ = _cluster()
    back = equal_area_vectors(equal_area_xy(poles))
    lower = np.where(poles[:, 2:3] > 0, -poles, poles)
    assert back == pytest.approx(lower, abs=1e-12)


def test_kamb_kappa_follows_vollmer():
    assert kamb_kappa(0) == 2.0 and kamb_kappa(90) == pytest.approx(22.0)


def test_contoured_stereonet_figure_draws_every_pole():
    poles, mean = _cluster()
    fig = plot_pole_density(poles, set_means=[mean])
    dots = [p for p in _scatter_points(fig.axes[0]) if p.shape == (poles.shape[0], 2)]
    assert dots and dots[0] == pytest.approx(equal_area_xy(poles))


# ----------------------------------------------------------------------------- scanline, RQD --


def _scanline():
    return Scanline(distance_m=[0.5, 0.55, 1.5, 3.0, 3.2, 6.0], dip_deg=[60, 62, 30, 61, 31, 59],
                    dip_direction_deg=[10, 12, 200, 8, 205, 11], trend_deg=0.0, plunge_deg=0.0, length_m=7.0)


def test_scanline_summary_holds_the_spacings_it_fitted_and_the_poles():
    line = _scanline()
    doc = scanline_statistics(line, membership=np.array([0, 0, 1, 0, 1, 0]))
    assert doc["all"]["spacings_m"] == pytest.approx([0.05, 0.95, 1.5, 0.2, 2.8])
    assert doc["sets"][0]["spacings_m"] == pytest.approx([0.05, 2.45, 3.0])   # set 0's hits only
    assert doc["all"]["spacing_m"]["n"] == len(doc["all"]["spacings_m"])
    assert doc["intersections"]["dip_deg"] == [60, 62, 30, 61, 31, 59]
    assert doc["intersections"]["distance_m"] == pytest.approx(line.distance_m.tolist())


def test_spacing_histogram_draws_the_fitted_densities_of_the_summary():
    doc = scanline_statistics(_scanline())
    fit = doc["all"]["spacing_m"]
    fig = plot_spacings([("all", doc["all"]["spacings_m"], fit), ("set 9", [], None)])
    ax, empty = fig.axes[:2]
    lam = fit["exponential"]["rate_per_m"]
    mu, sigma = fit["lognormal"]["mu_log_m"], fit["lognormal"]["sigma_log"]
    exp_line, log_line = ax.lines[:2]
    s = np.asarray(exp_line.get_xdata())
    assert exp_line.get_ydata() == pytest.approx(lam * np.exp(-lam * s))
    lognormal = np.exp(-0.5 * ((np.log(s) - mu) / sigma) ** 2) / (s * sigma * math.sqrt(2 * math.pi))
    assert log_line.get_ydata() == pytest.approx(lognormal)
    assert "no spacing" in empty.texts[0].get_text()


def test_rqd_bars_show_the_summary_values():
    fig = plot_rqd(["all", "set 0"], [97.5, 80.0], [73.58, None])
    heights = [p.get_height() for p in fig.axes[0].patches]
    assert heights == pytest.approx([97.5, 80.0, 73.58, 0.0])


# --------------------------------------------------------------------------------- contacts --


def test_two_slots_of_one_edge_contact_share_it_at_its_midpoint():
    # blocks 0 and 1 touch along y = 0 from x = 0 to x = 2 (slots at both ends, 1 m each); a
    # vertex-to-edge slot of blocks 1 and 2 stands for 2 m around (5, 5) along its tangent (0, 1)
    seg = contact_segments([[0, 0], [2, 0], [5, 5]], [[0, 1, 0], [0, 1, 0], [1, 0, 0]], [1, 1, 2],
                           [0, 0, 1], [1, 1, 2])
    assert seg.tolist() == [[[0, 0], [1, 0]], [[2, 0], [1, 0]], [[5, 4], [5, 6]]]
    lengths = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
    assert lengths == pytest.approx([1, 1, 2])          # each slot's segment is its contact length


def test_contact_map_colours_each_contact_by_its_value():
    from matplotlib.figure import Figure

    seg = contact_segments([[0, 0], [2, 0]], [[0, 1], [0, 1]], [1, 1], [0, 0], [1, 1])
    fig = Figure()
    ax = fig.add_subplot()
    coll = draw_contact_values(ax, seg, [0.5, -0.25], polygons=[np.array([[0, 0], [2, 0], [1, 1]])],
                               symmetric=True)
    assert coll.get_array().tolist() == [0.5, -0.25]
    low, high = coll.get_clim()
    assert low == -high and high > 0
