"""All trace-map statistics in one JSON-ready summary, keyed by names a fractopo user recognises.

:func:`trace_map_statistics` resolves the sampling window once and runs, on the traces that reach it:
joint sets (:mod:`~rockmass.dfn.sets2d`), P20 / P21 / mean length and scanline spacing
(:mod:`~rockmass.dfn.intensity`), Mauldon's estimators on the window when it is a circle, else on
disjoint circles placed inside it (:mod:`~rockmass.dfn.mauldon`), and the I-Y-X-E topology
(:mod:`~rockmass.dfn.topology`). Each parameter is ``{"value": number or None, "unit": str}``, with a ``"reason"`` when the value is None;
the names and units follow fractopo's ``Param`` (Ovaskainen et al. 2022). No NaN or infinity is ever
returned, so ``json.dumps(result, allow_nan=False)`` always succeeds.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely

from .intensity import (
    P20_RULES,
    _choice,
    _real_at_least,
    clipped_lengths_m,
    sampling_window,
    scanline_survey,
    trace_intensity,
)
from .mauldon import (
    CIRCLE_REL_TOLERANCE,
    InscribedCircles,
    MauldonEstimate,
    circle_window,
    inscribed_circles,
    mauldon_circle,
    mauldon_circles,
)
from .sets2d import RESOLUTION_DEG, JointSets2D, fit_sets_2d, trace_angles_deg
from .topology import trace_topology
from .tracemap import TraceMap, _require_trace_map

__all__ = ["trace_map_statistics"]

#: Default snap tolerance as a fraction of the window diameter: 1e-4 is 1 mm on a 10 m face and about
#: 0.7 px on a 24 MP photograph, close to fractopo's 1 mm default on outcrop maps of metres.
SNAP_FRACTION = 1e-4


def trace_map_statistics(
    trace_map: TraceMap,
    *,
    window: Any = None,
    n_sets: int | None = None,
    snap_tolerance_m: float | None = None,
    p20_rule: str = "endpoints",
    scanline_spacing_m: float | None = None,
    angle_method: str = "segments",
    resolution_deg: float = RESOLUTION_DEG,
    circle_rel_tolerance: float = CIRCLE_REL_TOLERANCE,
    mauldon_in_window: bool = True,
    seed: int = 0,
    length_unit: str = "m",
) -> dict:
    """Summarise a trace map: intensity, sets, Mauldon estimators, topology and trace lengths.

    Parameters
    ----------
    trace_map : TraceMap
        The traces, at least one reaching the window. Traces that miss the window are left out
        (counted under ``diagnostics``).
    window : array_like, shapely.Polygon or SamplingWindow, optional
        Sampling window; default None: the map's window, else the traces' bounding box
        (``result["window"]["source"]`` says which).
    n_sets : int, optional
        Number of joint sets; default None: chosen by BIC over 1..5.
    snap_tolerance_m : float, optional
        Snap distance for the topology and for ends on the window edge, >= 0. Default None:
        ``1e-4 ×`` the window diameter.
    p20_rule : {"endpoints", "midpoints"}, default "endpoints"
        P20 counting rule (see :mod:`rockmass.dfn.intensity`).
    scanline_spacing_m : float, optional
        Spacing of the scanlines laid normal to each set; default None: 10 scanlines per set.
    angle_method : {"segments", "chord"}, default "segments"
        Trace angle definition (see :func:`~rockmass.dfn.sets2d.trace_angles_deg`).
    resolution_deg, seed
        Passed to :func:`~rockmass.dfn.sets2d.fit_axial_mixture`.
    circle_rel_tolerance : float, default 0.01
        How close to a circle the window must be for Mauldon's estimators on the window itself
        (:func:`~rockmass.dfn.mauldon.circle_window`).
    mauldon_in_window : bool, default True
        When the window is not a circle, evaluate Mauldon's estimators on disjoint circles placed
        fully inside it (:func:`~rockmass.dfn.mauldon.inscribed_circles`, counts pooled by
        :func:`~rockmass.dfn.mauldon.mauldon_circles`); ``result["window"]["mauldon_circles"]``
        lists them. False: leave them undefined with a reason, as fractopo does.
    length_unit : str, default "m"
        Unit label of the map's coordinates (``"px"`` for a photo without scale); only the labels change.

    Returns
    -------
    dict
        JSON-ready. Parameters ``{"value", "unit"[, "reason"]}`` under their fractopo names:
        ``"Number of Traces"``, ``"Area"``, ``"Areal Frequency P20"``, ``"Fracture Intensity P21"``,
        ``"Trace Mean Length"``, ``"Trace Min Length"``, ``"Trace Max Length"``,
        ``"Dimensionless Intensity P22"``, ``"Number of Branches"``, ``"Connections per Trace"``,
        ``"Connections per Branch"``, ``"Connection Frequency"``, ``"Number of Censored Traces"``,
        ``"Fracture Intensity (Mauldon)"``, ``"Fracture Density (Mauldon)"``,
        ``"Trace Mean Length (Mauldon)"``; and

        - ``"Node Counts"``: ``{"I", "Y", "X", "E"}`` integers;
        - ``"sets"``: one dict per joint set (mean angle, spread, κ, weight, count, P20, P21, mean
          length raw and Mauldon, mean spacing and P10 along scanlines normal to the set);
        - ``"set_selection"``: ``{"method": "bic" | "given", "bic": {k: value or None}}``;
        - ``"traces"``: per trace ``id``, clipped ``length``, ``censored``, ``set``, ``angle_deg``,
          ``connections`` and ``end_class`` (the trace-length distribution with censoring marked);
        - ``"window"``: source, area, whether it is a circle (centre, radius), and the circles the
          Mauldon values were counted in when it is not (``"mauldon_circles"``: count, radius,
          centres; None when the window is a circle or ``mauldon_in_window`` is False);
        - ``"settings"`` and ``"diagnostics"``.

    Raises
    ------
    ValueError
        An empty map, no trace reaching the window, or a bad argument (the message names it).

    Notes
    -----
    The trace lengths are those inside the window (clipped), so the raw mean length, P21 and the
    censored flags describe the same observations; the set fit weights each trace by that length.
    Connections per trace use Sanderson & Nixon's node-count :math:`N_L = (N_I + N_Y)/2`, as fractopo
    does, while "Number of Traces" is the observed count.

    References
    ----------
    .. [1] Ovaskainen, N., Nordbäck, N., Skyttä, P., Engström, J. (2022). A new subsampling methodology
       to optimize the characterization of two-dimensional bedrock fracture networks. J. Struct. Geol.
       155, 104528 (fractopo).

    Examples
    --------
    >>> tm = TraceMap.from_segments([[1, 5, 9, 5], [5, 1, 5, 9]], window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    >>> s = trace_map_statistics(tm)
    >>> s["Fracture Intensity P21"], s["Node Counts"], s["Connections per Trace"]["value"]
    ({'value': 0.16, 'unit': 'm/m²'}, {'I': 4, 'Y': 0, 'X': 1, 'E': 0}, 1.0)
    """
    _require_trace_map(trace_map)
    if trace_map.n_traces == 0:
        raise ValueError("trace_map has 0 traces: there is nothing to analyse")
    if not isinstance(length_unit, str) or not length_unit.strip():
        raise TypeError(f"length_unit must be a non-empty string such as 'm' or 'px', got {length_unit!r}")
    _choice(p20_rule, P20_RULES, "p20_rule")
    resolution_deg = _real_at_least(
        resolution_deg, "resolution_deg", "angular resolution in degrees", above_zero=True
    )
    if scanline_spacing_m is not None:
        scanline_spacing_m = _real_at_least(
            scanline_spacing_m, "scanline_spacing_m", "distance between scanlines", above_zero=True
        )
    resolved = sampling_window(trace_map, window)
    reaches = shapely.intersects(trace_map.to_shapely(), resolved.polygon)
    if not reaches.any():
        raise ValueError(f"none of the {trace_map.n_traces} traces reaches the window (source: {resolved.source})")
    traces = trace_map if reaches.all() else trace_map.subset(reaches)
    if snap_tolerance_m is None:
        tolerance = SNAP_FRACTION * resolved.diameter_m
    else:
        tolerance = _real_at_least(snap_tolerance_m, "snap_tolerance_m", "snap distance in metres")
    circle = circle_window(resolved.polygon, rel_tolerance=circle_rel_tolerance)
    if not isinstance(mauldon_in_window, (bool, np.bool_)):
        raise TypeError(f"mauldon_in_window must be True or False, got {mauldon_in_window!r}")
    circles = inscribed_circles(resolved) if (mauldon_in_window and not circle.is_circle) else None

    topology = trace_topology(traces, snap_tolerance_m=tolerance, window=resolved)
    overall = trace_intensity(traces, window=resolved, p20_rule=p20_rule, edge_tolerance_m=tolerance)
    lengths = clipped_lengths_m(traces, resolved)
    angles = trace_angles_deg(traces, method=angle_method)
    sets = _fit_sets(traces, angles, lengths, n_sets, angle_method, resolution_deg, seed)
    u = _Units(length_unit)

    result: dict[str, Any] = {
        "Number of Traces": _quantity(traces.n_traces, "-"),
        "Area": _quantity(overall.area_m2, u.area),
        **_intensity_block(overall, lengths, u),
        "Dimensionless Intensity P22": _quantity(overall.p21_per_m * overall.mean_length_m, "-"),
        "Number of Branches": _quantity(topology.n_branches, "-"),
        "Connections per Trace": _quantity(
            topology.connections_per_line, "-", "no I or Y node: every trace end is censored (E)"
        ),
        "Connections per Branch": _quantity(topology.connections_per_branch, "-", "no branch (no I, Y or X node)"),
        "Connection Frequency": _quantity((topology.n_y + topology.n_x) / overall.area_m2, u.per_area),
        "Number of Censored Traces": _quantity(int(topology.censored.sum()), "-"),
        **_mauldon_block(traces, circle, circles, tolerance, u),
        "Node Counts": {"I": topology.n_i, "Y": topology.n_y, "X": topology.n_x, "E": topology.n_e},
        "sets": [],
        "set_selection": None,
    }
    membership = np.full(traces.n_traces, -1, dtype=np.int64)
    if isinstance(sets, JointSets2D):
        membership = sets.membership
        result["sets"] = [
            _set_block(traces, sets, s, resolved, p20_rule, tolerance, scanline_spacing_m, circle, circles, u)
            for s in range(sets.n_sets)
        ]
        result["set_selection"] = {
            "method": sets.selected_by,
            "bic": {str(k): _number(v) for k, v in sets.bic.items()},
        }
    else:
        result["set_selection"] = {"method": None, "bic": {}, "reason": sets}
    result["traces"] = {
        "id": traces.attributes["id"].tolist(),
        "length": [float(v) for v in lengths],
        "unit": u.length,
        "censored": topology.censored.tolist(),
        "set": membership.tolist(),
        "angle_deg": [_number(v) for v in angles],
        "connections": topology.connections.tolist(),
        "end_class": topology.end_class.tolist(),
    }
    result["window"] = {
        "source": resolved.source,
        "area": overall.area_m2,
        "unit": u.length,
        "is_circle": circle.is_circle,
        "centre_xy": list(circle.centre_xy_m) if circle.is_circle else None,
        "radius": circle.radius_m if circle.is_circle else None,
        "circle_deviation": _number(circle.max_rel_deviation),
        "mauldon_circles": None if circles is None else {
            "count": circles.n_circles,
            "radius": circles.radius_m,
            "centres_xy": circles.centres_xy_m.tolist(),
        },
    }
    result["settings"] = {
        "snap_tolerance": _quantity(topology.snap_tolerance_m, u.length),
        "p20_rule": p20_rule,
        "angle_method": angle_method,
        "n_sets": _number(n_sets),
        "resolution_deg": resolution_deg,
        "mauldon_in_window": bool(mauldon_in_window),
        "seed": _number(seed),
        "scanline_spacing": None if scanline_spacing_m is None else _quantity(scanline_spacing_m, u.length),
    }
    result["diagnostics"] = {
        "traces_outside_window": int(trace_map.n_traces - traces.n_traces),
        "zero_length_traces": int(np.count_nonzero(traces.degenerate_traces())),
        "end_contacts": int(topology.end_contact.sum()),
        "overlapping_pairs": topology.n_overlapping_pairs,
    }
    return result


class _Units:
    """Unit labels built from the map's length unit."""

    def __init__(self, length: str) -> None:
        self.length = length
        self.area = f"{length}²"
        self.intensity = f"{length}/{length}²"
        self.per_area = f"1/{length}²"
        self.per_length = f"1/{length}"


def _number(value: Any) -> float | int | None:
    """A JSON number, or None for NaN and infinities."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    value = float(value)
    return value if math.isfinite(value) else None


def _quantity(value: Any, unit: str, reason: str = "") -> dict:
    number = _number(value)
    out: dict[str, Any] = {"value": number, "unit": unit}
    if number is None:
        out["reason"] = reason or "undefined"
    return out


def _fit_sets(traces, angles, lengths, n_sets, angle_method, resolution_deg, seed) -> JointSets2D | str:
    """The set fit, or the reason there is none (no trace with a direction inside the window)."""
    if not np.any(np.isfinite(angles) & (lengths > 0.0)):
        return "no trace with a direction has a positive length inside the window"
    return fit_sets_2d(
        traces, n_sets, weights=lengths, method=angle_method, resolution_deg=resolution_deg, seed=seed
    )


def _intensity_block(intensity, lengths: np.ndarray, u: _Units) -> dict:
    reaching = lengths[lengths > 0.0]
    none = "no trace has a positive length inside the window"
    return {
        "Areal Frequency P20": _quantity(intensity.p20_per_m2, u.per_area),
        "Fracture Intensity P21": _quantity(intensity.p21_per_m, u.intensity),
        "Trace Mean Length": _quantity(intensity.mean_length_m, u.length, none),
        "Trace Min Length": _quantity(reaching.min() if reaching.size else None, u.length, none),
        "Trace Max Length": _quantity(reaching.max() if reaching.size else None, u.length, none),
    }


def _mauldon_block(traces: TraceMap, circle, circles: InscribedCircles | None, tolerance: float, u: _Units) -> dict:
    """Mauldon's values on the window when it is a circle, else pooled over ``circles`` (if any)."""
    names = ("Fracture Intensity (Mauldon)", "Fracture Density (Mauldon)", "Trace Mean Length (Mauldon)")
    units = (u.intensity, u.per_area, u.length)
    if circle.is_circle:
        estimate: MauldonEstimate = mauldon_circle(traces, circle.centre_xy_m, circle.radius_m, tolerance_m=tolerance)
    elif circles is not None:
        estimate = mauldon_circles(traces, circles, tolerance_m=tolerance)
    else:
        return {name: _quantity(None, unit, circle.reason) for name, unit in zip(names, units)}
    values = (estimate.p21_per_m, estimate.p20_per_m2, estimate.mean_length_m)
    return {name: _quantity(v, unit, estimate.reason) for name, v, unit in zip(names, values, units)}


def _set_block(traces, sets: JointSets2D, s: int, window, p20_rule, tolerance, spacing, circle, circles, u) -> dict:
    members = traces.subset(sets.membership == s)
    intensity = trace_intensity(members, window=window, p20_rule=p20_rule, edge_tolerance_m=tolerance)
    survey = scanline_survey(members, float(sets.mean_angle_deg[s]), window=window, line_spacing_m=spacing)
    lengths = clipped_lengths_m(members, window)
    block = {
        "Set": s,
        "Mean Angle": _quantity(sets.mean_angle_deg[s], "deg"),
        "Circular Spread": _quantity(sets.spread_deg[s], "deg", "the set has no preferred direction"),
        "Concentration (von Mises kappa)": _quantity(sets.kappa[s], "-"),
        "Concentration Capped": bool(sets.kappa_capped[s]),
        "Weight": _quantity(sets.weight[s], "-"),
        "Number of Traces": _quantity(int(sets.count[s]), "-"),
        **_intensity_block(intensity, lengths, u),
        **_mauldon_block(members, circle, circles, tolerance, u),
        "Mean Spacing": _quantity(survey.mean_spacing_m, u.length, survey.reason),
        "Scanline P10": _quantity(survey.p10_per_m, u.per_length, "the scanlines have zero length"),
        "Scanline Angle": _quantity(survey.scanline_angle_deg, "deg"),
        "Scanline Count": _quantity(int(survey.offsets_m.size), "-"),
        "Scanline Length": _quantity(survey.total_length_m, u.length),
        "Scanline Intersections": _quantity(survey.total_intersections, "-"),
    }
    return block
