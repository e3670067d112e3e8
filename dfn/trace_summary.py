"""The typed result of :func:`~rockmass.dfn.trace_stats.trace_map_statistics`.

:class:`TraceMapStatistics` is a frozen dataclass built of small frozen parts: a :class:`Parameter`
(value, unit and, when the value is undefined, the reason) for each fractopo parameter, the node
counts, one :class:`SetSummary` per joint set, the per-trace table, the window, the settings and the
diagnostics. Code reads the attributes (``stats.intensity.p21.value``, ``stats.traces.length``);
:meth:`TraceMapStatistics.to_dict` writes the JSON document keyed by fractopo's parameter names
(Ovaskainen et al. 2022) that ``summary.json`` holds. No NaN or infinity reaches that document, so
``json.dumps(stats.to_dict(), allow_nan=False)`` always succeeds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

__all__ = [
    "Diagnostics",
    "IntensityParameters",
    "MauldonCircleSet",
    "MauldonParameters",
    "NodeCounts",
    "P21Map",
    "Parameter",
    "SetSelection",
    "SetSummary",
    "StatisticsSettings",
    "TraceMapStatistics",
    "TraceTable",
    "ValidationSummary",
    "WindowSummary",
]


def _number(value: Any) -> float | int | bool | None:
    """A JSON number, or None for NaN and infinities."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    value = float(value)
    return value if math.isfinite(value) else None


def _by_field_name(part: Any) -> dict:
    """A part's JSON form when its keys are its field names: nested parts by their own ``to_dict()``."""
    values = ((f.name, getattr(part, f.name)) for f in fields(part))
    return {name: value.to_dict() if hasattr(value, "to_dict") else value for name, value in values}


@dataclass(frozen=True)
class Parameter:
    """One named quantity: a finite number with its unit, or None with the reason it is undefined.

    Attributes
    ----------
    value : float, int or None
        The value; None when it is undefined (NaN and infinities become None).
    unit : str
        Unit label, built from the map's length unit (``"m/m²"``, ``"px"``) or ``"-"``, ``"deg"``.
    reason : str or None
        Why ``value`` is None; None whenever ``value`` is a number.
    """

    value: float | int | None
    unit: str
    reason: str | None = None

    @classmethod
    def of(cls, value: Any, unit: str, reason: str = "") -> Parameter:
        """``value`` as a JSON number (NaN and infinities → None), with ``reason`` (default
        ``"undefined"``) kept only when the value is None."""
        number = _number(value)
        return cls(number, unit, (reason or "undefined") if number is None else None)

    def to_dict(self) -> dict:
        """``{"value", "unit"}``, plus ``"reason"`` when the value is None."""
        out: dict[str, Any] = {"value": self.value, "unit": self.unit}
        if self.value is None:
            out["reason"] = self.reason
        return out


@dataclass(frozen=True)
class IntensityParameters:
    """Counts and lengths inside the window, for the whole map or one set.

    Attributes
    ----------
    p20 : Parameter
        "Areal Frequency P20", traces per unit area (1/length²).
    p21 : Parameter
        "Fracture Intensity P21", trace length per unit area (length/length²).
    mean_length, min_length, max_length : Parameter
        "Trace Mean Length", "Trace Min Length", "Trace Max Length" of the clipped traces of positive
        length.
    """

    p20: Parameter
    p21: Parameter
    mean_length: Parameter
    min_length: Parameter
    max_length: Parameter

    def to_dict(self) -> dict:
        return {
            "Areal Frequency P20": self.p20.to_dict(),
            "Fracture Intensity P21": self.p21.to_dict(),
            "Trace Mean Length": self.mean_length.to_dict(),
            "Trace Min Length": self.min_length.to_dict(),
            "Trace Max Length": self.max_length.to_dict(),
        }


@dataclass(frozen=True)
class MauldonParameters:
    """Mauldon's circle estimators, on the window when it is a circle, else pooled over inscribed circles.

    Attributes
    ----------
    p21 : Parameter
        "Fracture Intensity (Mauldon)" (length/length²).
    p20 : Parameter
        "Fracture Density (Mauldon)" (1/length²).
    mean_length : Parameter
        "Trace Mean Length (Mauldon)".
    """

    p21: Parameter
    p20: Parameter
    mean_length: Parameter

    def to_dict(self) -> dict:
        return {
            "Fracture Intensity (Mauldon)": self.p21.to_dict(),
            "Fracture Density (Mauldon)": self.p20.to_dict(),
            "Trace Mean Length (Mauldon)": self.mean_length.to_dict(),
        }


@dataclass(frozen=True)
class NodeCounts:
    """Topological node counts: isolated ends (I), abutments (Y), crossings (X), censored ends (E)."""

    i: int
    y: int
    x: int
    e: int

    def to_dict(self) -> dict:
        return {"I": self.i, "Y": self.y, "X": self.x, "E": self.e}


@dataclass(frozen=True)
class P21Map:
    """P21 on a grid of square cells laid over the window (the "P21 Map" of ``summary.json``).

    Cell (row j, column i) covers ``[x0 + i s, x0 + (i+1) s) × [y0 + j s, y0 + (j+1) s)``, with
    (x0, y0) = ``origin_xy`` the lower-left corner of the window's bounding box and s =
    ``cell_size``; row 0 is the bottom row. Each trace, clipped to the window, is cut where it
    crosses a grid line and every piece is given to the one cell that holds its midpoint, so the
    cells' lengths add up to the total trace length inside the window (no piece is counted twice,
    even along a grid line).

    Attributes
    ----------
    origin_xy : tuple of float
        Lower-left corner of the grid, in the map's length unit.
    cell_size : float
        Side s of a cell, in the map's length unit.
    length : (ny, nx) float ndarray
        Trace length inside each cell and the window.
    area : (ny, nx) float ndarray
        Area of each cell inside the window (0 for a cell outside it).
    p21 : (ny, nx) float ndarray
        ``length / area``; NaN where ``area`` is 0 (None in the JSON document).
    unit : str
        The map's length unit.
    """

    origin_xy: tuple[float, float]
    cell_size: float
    length: np.ndarray
    area: np.ndarray
    p21: np.ndarray
    unit: str

    def to_dict(self) -> dict:
        return {
            "origin_xy": [float(v) for v in self.origin_xy],
            "cell_size": float(self.cell_size),
            "shape": list(self.length.shape),
            "length": self.length.tolist(),
            "area": self.area.tolist(),
            "p21": [[_number(v) for v in row] for row in self.p21],
            "unit": self.unit,
            "p21_unit": f"{self.unit}/{self.unit}²",
        }


@dataclass(frozen=True)
class SetSummary:
    """One joint set of the trace map.

    Attributes
    ----------
    index : int
        The set's number, as in :attr:`TraceTable.set_id`.
    mean_angle, circular_spread : Parameter
        Mean trace angle (in the result's ``angle_convention``: azimuth on a map, counter-clockwise
        from +u on a face) and circular spread, deg.
    kappa : Parameter
        von Mises concentration of the fitted axial mixture.
    kappa_capped : bool
        True when the fit reached the concentration cap.
    weight : Parameter
        Mixture weight (share of the length-weighted traces).
    n_traces : Parameter
        Traces assigned to the set.
    intensity : IntensityParameters
        P20, P21 and lengths of the set's traces in the window.
    mauldon : MauldonParameters
        Mauldon's estimators on the set's traces.
    mean_spacing, scanline_p10, scanline_angle, scanline_count, scanline_length, scanline_intersections : Parameter
        The survey along scanlines laid normal to the set (:func:`~rockmass.dfn.intensity.scanline_survey`).
    """

    index: int
    mean_angle: Parameter
    circular_spread: Parameter
    kappa: Parameter
    kappa_capped: bool
    weight: Parameter
    n_traces: Parameter
    intensity: IntensityParameters
    mauldon: MauldonParameters
    mean_spacing: Parameter
    scanline_p10: Parameter
    scanline_angle: Parameter
    scanline_count: Parameter
    scanline_length: Parameter
    scanline_intersections: Parameter

    def to_dict(self) -> dict:
        return {
            "Set": self.index,
            "Mean Angle": self.mean_angle.to_dict(),
            "Circular Spread": self.circular_spread.to_dict(),
            "Concentration (von Mises kappa)": self.kappa.to_dict(),
            "Concentration Capped": self.kappa_capped,
            "Weight": self.weight.to_dict(),
            "Number of Traces": self.n_traces.to_dict(),
            **self.intensity.to_dict(),
            **self.mauldon.to_dict(),
            "Mean Spacing": self.mean_spacing.to_dict(),
            "Scanline P10": self.scanline_p10.to_dict(),
            "Scanline Angle": self.scanline_angle.to_dict(),
            "Scanline Count": self.scanline_count.to_dict(),
            "Scanline Length": self.scanline_length.to_dict(),
            "Scanline Intersections": self.scanline_intersections.to_dict(),
        }


@dataclass(frozen=True)
class SetSelection:
    """How the number of sets was chosen.

    Attributes
    ----------
    method : str or None
        ``"bic"`` or ``"given"``; None when no set was fitted.
    bic : dict of str to float or None
        BIC per tried number of sets (keys are the numbers as strings, as in the JSON document).
    reason : str or None
        Why no set was fitted; None when sets were fitted.
    """

    method: str | None
    bic: dict[str, float | None]
    reason: str | None = None

    def to_dict(self) -> dict:
        out: dict[str, Any] = {"method": self.method, "bic": dict(self.bic)}
        if self.reason is not None:
            out["reason"] = self.reason
        return out


@dataclass(frozen=True)
class TraceTable:
    """Per-trace values, one entry per trace reaching the window (structure of arrays).

    Attributes
    ----------
    id : (N,) ndarray
        The traces' ``id`` attribute.
    length : (N,) float ndarray
        Length inside the window, in ``unit``.
    unit : str
        The map's length unit.
    censored : (N,) bool ndarray
        True when an end of the trace is censored by the window edge.
    set_id : (N,) int ndarray
        Index of the trace's set, -1 when it has none.
    angle_deg : (N,) float ndarray
        Trace angle, deg, in the result's ``angle_convention``; NaN for a trace without direction
        (None in the JSON document).
    connections : (N,) int ndarray
        Y and X nodes on the trace.
    end_class : (N,) ndarray
        Topological class of the trace's ends.
    validation_errors : tuple of tuple of str
        Per trace, its fractopo validation labels (:mod:`~rockmass.dfn.trace_validation`); empty
        for a clean trace.
    """

    id: np.ndarray
    length: np.ndarray
    unit: str
    censored: np.ndarray
    set_id: np.ndarray
    angle_deg: np.ndarray
    connections: np.ndarray
    end_class: np.ndarray
    validation_errors: tuple[tuple[str, ...], ...]

    def to_dict(self) -> dict:
        return {
            "id": self.id.tolist(),
            "length": [float(v) for v in self.length],
            "unit": self.unit,
            "censored": self.censored.tolist(),
            "set": self.set_id.tolist(),
            "angle_deg": [_number(v) for v in self.angle_deg],
            "connections": self.connections.tolist(),
            "end_class": self.end_class.tolist(),
            "validation_errors": [list(labels) for labels in self.validation_errors],
        }


@dataclass(frozen=True)
class ValidationSummary:
    """How many traces fractopo's validation would flag, by label (:func:`~rockmass.dfn.validate_traces`).

    Attributes
    ----------
    n_flagged : int
        Traces with at least one defect.
    counts : dict of str to int
        Traces flagged with each label (every label checked, zeros included).
    sharp_turn_deg : float
        The turn limit of ``SHARP TURNS``, deg.
    snap_tolerance : Parameter
        The snap tolerance of the node checks, in the map's length unit.
    """

    n_flagged: int
    counts: dict[str, int]
    sharp_turn_deg: float
    snap_tolerance: Parameter

    def to_dict(self) -> dict:
        return {"traces_flagged": self.n_flagged, "errors": dict(self.counts),
                "sharp_turn_deg": self.sharp_turn_deg, "snap_tolerance": self.snap_tolerance.to_dict(),
                "labels": "fractopo's VALIDATION_ERRORS labels (fractopo.tval); per trace under traces"}


@dataclass(frozen=True)
class MauldonCircleSet:
    """Disjoint circles inside a non-circular window in which Mauldon's counts were pooled.

    Attributes
    ----------
    count : int
        Number of circles.
    radius : float
        Their common radius, in the map's length unit.
    centres_xy : (count, 2) float ndarray
        Their centres.
    """

    count: int
    radius: float
    centres_xy: np.ndarray

    def to_dict(self) -> dict:
        return {"count": self.count, "radius": self.radius, "centres_xy": self.centres_xy.tolist()}


@dataclass(frozen=True)
class WindowSummary:
    """The sampling window the statistics were computed on.

    Attributes
    ----------
    source : str
        Where it came from: ``"argument"`` (given), ``"trace_map"`` (the map's own window), or the
        explicit stand-ins ``"bounding_box"`` / ``"convex_hull"`` of the traces.
    area : float
        Its area, in ``unit`` squared.
    unit : str
        The map's length unit.
    is_circle : bool
        True when it is close enough to a circle for Mauldon's estimators on the window itself.
    centre_xy : tuple of float or None
        The circle's centre; None when it is not a circle.
    radius : float or None
        The circle's radius; None when it is not a circle.
    circle_deviation : float or None
        Largest relative deviation of the boundary from the fitted circle.
    mauldon_circles : MauldonCircleSet or None
        The inscribed circles of Mauldon's values; None when the window is a circle or they were not
        asked for.
    """

    source: str
    area: float
    unit: str
    is_circle: bool
    centre_xy: tuple[float, float] | None
    radius: float | None
    circle_deviation: float | None
    mauldon_circles: MauldonCircleSet | None

    def to_dict(self) -> dict:
        centre = None if self.centre_xy is None else list(self.centre_xy)
        return {**_by_field_name(self), "centre_xy": centre}


@dataclass(frozen=True)
class StatisticsSettings:
    """The settings the statistics were computed with (defaults resolved).

    Attributes
    ----------
    snap_tolerance : Parameter
        Topology snap distance, in the map's length unit.
    p20_rule, angle_method : str
        As passed to :func:`~rockmass.dfn.trace_stats.trace_map_statistics`.
    n_sets : int or None
        The requested number of sets; None when chosen by BIC.
    resolution_deg : float
        Angular resolution of the set fit.
    mauldon_in_window : bool
        Whether Mauldon's estimators were evaluated on circles inside a non-circular window.
    seed : int or None
        Seed of the set fit.
    scanline_spacing : Parameter or None
        Requested scanline spacing; None for the default of 10 scanlines per set.
    """

    snap_tolerance: Parameter
    p20_rule: str
    angle_method: str
    n_sets: int | None
    resolution_deg: float
    mauldon_in_window: bool
    seed: int | None
    scanline_spacing: Parameter | None

    def to_dict(self) -> dict:
        return _by_field_name(self)


@dataclass(frozen=True)
class Diagnostics:
    """Counts that flag suspicious input.

    Attributes
    ----------
    traces_outside_window : int
        Traces of the map left out because they miss the window.
    zero_length_traces : int
        Degenerate traces (all vertices coincide).
    end_contacts : int
        Trace ends that touch another trace's end.
    overlapping_pairs : int
        Pairs of traces that overlap along a stretch.
    """

    traces_outside_window: int
    zero_length_traces: int
    end_contacts: int
    overlapping_pairs: int

    def to_dict(self) -> dict:
        return _by_field_name(self)


@dataclass(frozen=True)
class TraceMapStatistics:
    """All statistics of a trace map (see :func:`~rockmass.dfn.trace_stats.trace_map_statistics`).

    Attributes
    ----------
    n_traces : Parameter
        "Number of Traces": traces reaching the window.
    area : Parameter
        "Area" of the window.
    intensity : IntensityParameters
        P20, P21 and trace lengths of all traces.
    p22 : Parameter
        "Dimensionless Intensity P22" (P21 × mean length).
    n_branches : Parameter
        "Number of Branches".
    connections_per_trace, connections_per_branch : Parameter
        "Connections per Trace" (Sanderson & Nixon's node count) and "Connections per Branch".
    connection_frequency : Parameter
        "Connection Frequency": Y and X nodes per unit area.
    n_censored : Parameter
        "Number of Censored Traces".
    mauldon : MauldonParameters
        Mauldon's estimators on all traces.
    node_counts : NodeCounts
        "Node Counts".
    sets : tuple of SetSummary
        One per joint set, in set order; empty when no set was fitted.
    set_selection : SetSelection
        How the number of sets was chosen.
    traces : TraceTable
        The per-trace table.
    window : WindowSummary
        The sampling window.
    settings : StatisticsSettings
        The settings used.
    frame : str
        The map's frame (``"map"``, ``"face"``, ``"plane"``, ...).
    crs : str or None
        The map's coordinate reference system; None for a face or section frame.
    angle_convention : str
        ``"azimuth"`` or ``"face"`` (:data:`rockmass.dfn.frames.ANGLE_CONVENTIONS`): the convention of
        every angle of the result (per trace, set means, scanline directions).
    diagnostics : Diagnostics
        Counts that flag suspicious input.
    p21_map : P21Map
        "P21 Map": P21 on square cells over the window.
    validation : ValidationSummary
        Traces fractopo's validation would flag, by label.
    """

    n_traces: Parameter
    area: Parameter
    intensity: IntensityParameters
    p22: Parameter
    n_branches: Parameter
    connections_per_trace: Parameter
    connections_per_branch: Parameter
    connection_frequency: Parameter
    n_censored: Parameter
    mauldon: MauldonParameters
    node_counts: NodeCounts
    sets: tuple[SetSummary, ...]
    set_selection: SetSelection
    traces: TraceTable
    window: WindowSummary
    settings: StatisticsSettings
    frame: str
    crs: str | None
    angle_convention: str
    diagnostics: Diagnostics
    p21_map: P21Map
    validation: ValidationSummary

    def to_dict(self) -> dict:
        """The JSON document: parameters under their fractopo names, then ``"Node Counts"``,
        ``"sets"``, ``"set_selection"``, ``"traces"``, ``"window"``, ``"settings"``, ``"frame"``,
        ``"crs"``, ``"angle_convention"`` with its meaning in ``"angle_convention_text"``,
        ``"diagnostics"``, ``"P21 Map"`` and ``"validation"`` (a new dict on each call)."""
        from .frames import ANGLE_CONVENTIONS

        return {
            "Number of Traces": self.n_traces.to_dict(),
            "Area": self.area.to_dict(),
            **self.intensity.to_dict(),
            "Dimensionless Intensity P22": self.p22.to_dict(),
            "Number of Branches": self.n_branches.to_dict(),
            "Connections per Trace": self.connections_per_trace.to_dict(),
            "Connections per Branch": self.connections_per_branch.to_dict(),
            "Connection Frequency": self.connection_frequency.to_dict(),
            "Number of Censored Traces": self.n_censored.to_dict(),
            **self.mauldon.to_dict(),
            "Node Counts": self.node_counts.to_dict(),
            "sets": [s.to_dict() for s in self.sets],
            "set_selection": self.set_selection.to_dict(),
            "traces": self.traces.to_dict(),
            "window": self.window.to_dict(),
            "settings": self.settings.to_dict(),
            "frame": self.frame,
            "crs": self.crs,
            "angle_convention": self.angle_convention,
            "angle_convention_text": ANGLE_CONVENTIONS[self.angle_convention],
            "diagnostics": self.diagnostics.to_dict(),
            "P21 Map": self.p21_map.to_dict(),
            "validation": self.validation.to_dict(),
        }
