"""Scanline surveys: joints hit along a straight line, with the line's orientation and length.

A :class:`Scanline` holds, per intersection, the distance along the line (metres from its start),
the orientation of the joint plane (dip / dip direction, docs/fractures.md §1.1) and optionally the trace
length and a termination code; and, for the line, its trend, plunge (positive downward) and length,
and optionally its start point in the world frame (x East, y North, z Up).

:func:`read_scanline` reads the CSV a field geologist fills in::

    # trend: 45
    # plunge: 10
    # length: 30
    distance,dip,dip_direction,trace_length,termination
    0.42,52,268,7.5,1
    ...

Columns (case-insensitive, in any order; a ``_m`` / ``_deg`` unit suffix is accepted):
``distance`` (m), ``dip`` (0–90°) and either ``dip_direction`` (°, clockwise from North) or
``strike`` (°, right-hand rule: the plane dips to the right looking along the strike); optional
``trace_length`` (m, blank when not measured) and ``termination`` (free text, e.g. the number of
visible trace ends). The line's geometry comes from ``# key: value`` comments before the column row
(``trend``, ``plunge``, ``length``, optional ``start`` as ``x, y, z``) or from a TOML file beside the
CSV with the same stem (``survey.csv`` → ``survey.toml``)::

    [scanline]
    trend_deg = 45.0
    plunge_deg = 10.0
    length_m = 30.0
    start_xyz_m = [0.0, 0.0, 0.0]   # optional

If both give a value, they must agree. Every defect is a ``ValueError`` naming the file, the line
number and the column.
"""

from __future__ import annotations

import csv
import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .orientation import _as_scalar, _wrap360, dip_from_strike, pole_from_dip, vector_from_trend_plunge

__all__ = ["Scanline", "read_scanline"]

#: Column name -> canonical field; unit suffixes are stripped before the look-up.
_COLUMNS = {
    "distance": "distance", "dip": "dip", "dip_direction": "dip_direction", "dipdir": "dip_direction",
    "dip_dir": "dip_direction", "strike": "strike", "trace_length": "trace_length",
    "termination": "termination",
}
#: Geometry keys in header comments -> canonical key (TOML uses the unit-suffixed names only).
_HEADER_KEYS = {"trend": "trend_deg", "trend_deg": "trend_deg", "plunge": "plunge_deg",
                "plunge_deg": "plunge_deg", "length": "length_m", "length_m": "length_m",
                "start": "start_xyz_m", "start_xyz_m": "start_xyz_m"}
_TOML_KEYS = ("trend_deg", "plunge_deg", "length_m", "start_xyz_m")


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=np.float64, copy=True)
    array.flags.writeable = False
    return array


@dataclass(frozen=True)
class Scanline:
    """One scanline survey (structure of arrays; every array has one entry per intersection).

    Attributes
    ----------
    distance_m : (n,) ndarray of float64
        Distance of each intersection from the line's start, metres, non-decreasing, in
        [0, ``length_m``].
    dip_deg : (n,) ndarray of float64
        Dip of each joint plane, [0, 90] degrees.
    dip_direction_deg : (n,) ndarray of float64
        Dip direction, [0, 360) degrees clockwise from North.
    trend_deg : float
        Trend of the line, [0, 360) degrees (the direction of increasing distance).
    plunge_deg : float
        Plunge of the line, [-90, 90] degrees, positive downward.
    length_m : float
        Surveyed length of the line, > 0 metres.
    trace_length_m : (n,) ndarray of float64 or None
        Trace length of each joint, metres (NaN where not measured); None without the column.
    termination : tuple of str or None
        Termination code of each joint as written ("" where blank); None without the column.
    start_xyz_m : (3,) ndarray of float64 or None
        Start point in the world frame (x East, y North, z Up), if known.
    source : str or None
        The file it was read from.
    """

    distance_m: np.ndarray
    dip_deg: np.ndarray
    dip_direction_deg: np.ndarray
    trend_deg: float
    plunge_deg: float
    length_m: float
    trace_length_m: np.ndarray | None = None
    termination: tuple | None = None
    start_xyz_m: np.ndarray | None = None
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        length = _as_scalar(self.length_m, "length_m", low=0.0, low_open=True, what="scanline length in metres")
        trend = _as_scalar(self.trend_deg, "trend_deg", what="scanline trend in degrees")
        plunge = _as_scalar(self.plunge_deg, "plunge_deg", low=-90.0, high=90.0,
                            what="scanline plunge in degrees, positive downward")
        distance = np.asarray(self.distance_m, dtype=np.float64).reshape(-1)
        n = distance.size
        arrays = {"distance_m": distance}
        for name in ("dip_deg", "dip_direction_deg"):
            arrays[name] = np.asarray(getattr(self, name), dtype=np.float64).reshape(-1)
        if self.trace_length_m is not None:
            arrays["trace_length_m"] = np.asarray(self.trace_length_m, dtype=np.float64).reshape(-1)
        for name, array in arrays.items():
            if array.size != n:
                raise ValueError(f"{name} must have one value per intersection ({n}), got {array.size}")
            finite = np.isfinite(array) | (name == "trace_length_m")  # NaN trace length = not measured
            if not finite.all() or np.isinf(array).any():
                raise ValueError(f"{name} must be finite, bad at indices {np.flatnonzero(~np.isfinite(array))[:10].tolist()}")
        if ((distance < 0) | (distance > length)).any():
            bad = np.flatnonzero((distance < 0) | (distance > length))[:10].tolist()
            raise ValueError(f"distance_m must be in [0, length_m = {length:g}] m, bad at indices {bad}")
        if (np.diff(distance) < 0).any():
            bad = (np.flatnonzero(np.diff(distance) < 0) + 1)[:10].tolist()
            raise ValueError(f"distance_m must be non-decreasing along the line, decreases at indices {bad}")
        dip = arrays["dip_deg"]
        if ((dip < 0) | (dip > 90)).any():
            raise ValueError(f"dip_deg must be in [0, 90] degrees, got {dip[(dip < 0) | (dip > 90)][:10].tolist()}")
        if "trace_length_m" in arrays and (arrays["trace_length_m"] < 0).any():
            raise ValueError("trace_length_m must be >= 0 metres (NaN where not measured)")
        termination = self.termination
        if termination is not None:
            termination = tuple(str(t) for t in termination)
            if len(termination) != n:
                raise ValueError(f"termination must have one value per intersection ({n}), got {len(termination)}")
        start = self.start_xyz_m
        if start is not None:
            start = np.asarray(start, dtype=np.float64)
            if start.shape != (3,) or not np.isfinite(start).all():
                raise ValueError(f"start_xyz_m must be 3 finite numbers (x East, y North, z Up), got {self.start_xyz_m!r}")
        set_ = object.__setattr__
        set_(self, "distance_m", _frozen(distance))
        set_(self, "dip_deg", _frozen(dip))
        set_(self, "dip_direction_deg", _frozen(_wrap360(arrays["dip_direction_deg"])))
        set_(self, "trace_length_m", None if self.trace_length_m is None else _frozen(arrays["trace_length_m"]))
        set_(self, "termination", termination)
        set_(self, "start_xyz_m", None if start is None else _frozen(start))
        set_(self, "trend_deg", float(_wrap360(np.float64(trend))))
        set_(self, "plunge_deg", plunge)
        set_(self, "length_m", length)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scanline):
            return NotImplemented
        def same(a, b):
            if a is None or b is None:
                return a is b
            return np.array_equal(a, b, equal_nan=True)
        return (self.trend_deg, self.plunge_deg, self.length_m, self.termination) == (
            other.trend_deg, other.plunge_deg, other.length_m, other.termination) and all(
            same(getattr(self, name), getattr(other, name))
            for name in ("distance_m", "dip_deg", "dip_direction_deg", "trace_length_m", "start_xyz_m"))

    __hash__ = None  # arrays inside: equal by value, not hashable

    @property
    def n_intersections(self) -> int:
        """Number of joints hit."""
        return int(self.distance_m.size)

    @property
    def direction(self) -> np.ndarray:
        """Unit vector of the line (trend / plunge, plunge positive downward), ``(3,)`` float64."""
        return vector_from_trend_plunge(self.trend_deg, self.plunge_deg)

    def poles(self) -> np.ndarray:
        """Lower-hemisphere unit poles of the joints, ``(n, 3)`` float64 (x East, y North, z Up)."""
        return pole_from_dip(self.dip_deg, self.dip_direction_deg).reshape(-1, 3)

    def spacings_m(self) -> np.ndarray:
        """Distances between consecutive intersections along the line, ``(n - 1,)`` float64."""
        return np.diff(self.distance_m)


# -- reading --------------------------------------------------------------------------------------


def _canonical(name: str) -> str:
    key = name.strip().lower().replace(" ", "_")
    for suffix in ("_deg", "_m"):
        if key.endswith(suffix) and key[: -len(suffix)] in _COLUMNS:
            key = key[: -len(suffix)]
    return key


def _number(text: str, where: str, column: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{where}, column '{column}': expected a number ({what}), got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{where}, column '{column}': must be a finite number ({what}), got {text!r}")
    return value


def _header_value(key: str, text: str, where: str):
    if key == "start_xyz_m":
        parts = [p for p in text.replace(";", ",").replace(" ", ",").split(",") if p]
        if len(parts) != 3:
            raise ValueError(f"{where}: start must be 'x, y, z' in metres, got {text!r}")
        return [_number(p, where, "start", "metres") for p in parts]
    return _number(text, where, key.split("_")[0], "scanline geometry")


def _read_toml(path: Path) -> dict:
    try:
        with open(path, "rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    table = data.get("scanline", data)
    if not isinstance(table, dict):
        raise ValueError(f"{path}: scanline: must be a table with {', '.join(_TOML_KEYS)}")
    prefix = "scanline." if "scanline" in data else ""
    extra = set(data) - {"scanline"} if prefix else set()
    unknown = sorted((set(table) - set(_TOML_KEYS)) | extra)
    if unknown:
        raise ValueError(f"{path}: {prefix}{unknown[0]}: unknown key; allowed: {', '.join(_TOML_KEYS)}")
    geometry = {}
    for key, value in table.items():
        if key == "start_xyz_m":
            ok = isinstance(value, list) and len(value) == 3 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
            if not ok:
                raise ValueError(f"{path}: {prefix}{key}: must be [x, y, z] in metres, got {value!r}")
            geometry[key] = [float(v) for v in value]
        else:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{path}: {prefix}{key}: must be a finite number, got {value!r}")
            geometry[key] = float(value)
    return geometry


def _check_geometry(geometry: dict, path: Path, sources: dict) -> None:
    for key in ("trend_deg", "plunge_deg", "length_m"):
        if key not in geometry:
            raise ValueError(
                f"{path}: scanline {key.split('_')[0]} is missing: give it as a '# {key.split('_')[0]}: "
                f"...' header comment or as {key} in {path.with_suffix('.toml').name}")
    checks = (("plunge_deg", -90.0, 90.0, "degrees, positive downward"),
              ("length_m", 0.0, math.inf, "metres, > 0"))
    for key, low, high, what in checks:
        value = geometry[key]
        if not (low <= value <= high) or (key == "length_m" and value <= 0):
            raise ValueError(f"{sources[key]}: {key.split('_')[0]} must be in {what}, got {value:g}")


def read_scanline(path: str | os.PathLike) -> Scanline:
    """Read a scanline survey CSV (and the TOML beside it, if any).

    Parameters
    ----------
    path : str or path-like
        The CSV file; its format is in the module docstring.

    Returns
    -------
    Scanline

    Raises
    ------
    ValueError
        Naming the file, line number and column: no data rows, a missing or duplicated column, a
        value that is not a finite number (NaN included), a dip outside 0–90°, distances beyond the
        line length or not in increasing order, missing or disagreeing line geometry, unknown TOML
        keys.
    OSError
        The file cannot be read.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> _ = p.write_text("# trend: 90\\n# plunge: 0\\n# length: 5\\ndistance,strike,dip\\n1.0,0,30\\n")
    >>> s = read_scanline(p)
    >>> s.n_intersections, float(s.dip_direction_deg[0]), float(s.length_m)
    (1, 90.0, 5.0)
    """
    path = Path(path)
    with open(path, encoding="utf-8-sig", newline="") as handle:
        lines = handle.read().splitlines()
    header: dict = {}
    sources: dict = {}
    rows: list[tuple[int, list[str]]] = []
    columns: list[str] | None = None
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        where = f"{path}: line {number}"
        if not stripped:
            continue
        if stripped.startswith("#"):
            body = stripped.lstrip("#").strip()
            if ":" in body and columns is None:
                key, _, value = body.partition(":")
                canonical = _HEADER_KEYS.get(key.strip().lower())
                if canonical is not None:
                    if canonical in header:
                        raise ValueError(f"{where}: header gives {key.strip()} twice")
                    header[canonical] = _header_value(canonical, value.strip(), where)
                    sources[canonical] = where
            continue
        cells = next(csv.reader([line]))
        if columns is None:
            columns = [_canonical(c) for c in cells]
            known = [c for c in columns if c in _COLUMNS]
            for c, raw in zip(columns, cells):
                if c not in _COLUMNS:
                    raise ValueError(f"{where}, column '{raw.strip()}': unknown column; expected distance, dip, "
                                     "dip_direction (or strike, right-hand rule), optional trace_length, termination")
            canon = [_COLUMNS[c] for c in known]
            duplicated = sorted({c for c in canon if canon.count(c) > 1})
            if duplicated:
                raise ValueError(f"{where}, column '{duplicated[0]}': given twice")
            columns = canon
            if "distance" not in columns or "dip" not in columns:
                missing = "distance" if "distance" not in columns else "dip"
                raise ValueError(f"{where}, column '{missing}': required column is missing")
            if ("dip_direction" in columns) == ("strike" in columns):
                raise ValueError(f"{where}, column 'dip_direction': give exactly one of dip_direction "
                                 "or strike (right-hand rule)")
            header_line = number
            continue
        rows.append((number, cells))
    if columns is None:
        raise ValueError(f"{path}: empty scanline file: no column row (distance, dip, dip_direction ...)")
    if not rows:
        raise ValueError(f"{path}: line {header_line}: no intersections below the column row; an empty "
                         "scanline cannot be analysed")
    toml_path = path.with_suffix(".toml")
    geometry = dict(header)
    if toml_path.is_file():
        for key, value in _read_toml(toml_path).items():
            if key in geometry and not np.allclose(geometry[key], value, rtol=1e-12, atol=1e-12):
                raise ValueError(f"{sources[key]}: {key.split('_')[0]} = {geometry[key]} disagrees with "
                                 f"{toml_path}: {key} = {value}")
            geometry[key] = value
            sources.setdefault(key, f"{toml_path}: {key}")
    _check_geometry(geometry, path, sources)
    length = geometry["length_m"]

    values = {c: [] for c in columns}
    what = {"distance": "metres along the line", "dip": "degrees, 0-90", "dip_direction": "degrees",
            "strike": "degrees, right-hand rule", "trace_length": "metres, blank if not measured"}
    previous = -math.inf
    for number, cells in rows:
        where = f"{path}: line {number}"
        if len(cells) != len(columns):
            raise ValueError(f"{where}: expected {len(columns)} columns ({', '.join(columns)}), got {len(cells)}")
        for column, text in zip(columns, cells):
            text = text.strip()
            if column == "termination":
                values[column].append(text)
                continue
            if column == "trace_length" and text == "":
                values[column].append(math.nan)
                continue
            value = _number(text, where, column, what[column])
            if column == "dip" and not 0.0 <= value <= 90.0:
                raise ValueError(f"{where}, column 'dip': must be in [0, 90] degrees, got {value:g}")
            if column == "trace_length" and value < 0:
                raise ValueError(f"{where}, column 'trace_length': must be >= 0 metres, got {value:g}")
            if column == "distance":
                if not 0.0 <= value <= length:
                    raise ValueError(f"{where}, column 'distance': {value:g} m is outside the scanline "
                                     f"[0, length = {length:g} m]")
                if value < previous:
                    raise ValueError(f"{where}, column 'distance': {value:g} m is less than the previous "
                                     f"{previous:g} m; distances must be in increasing order")
                previous = value
            values[column].append(value)
    if "strike" in values:
        dip, direction = dip_from_strike(values["strike"], values["dip"])
    else:
        dip, direction = np.asarray(values["dip"]), np.asarray(values["dip_direction"])
    return Scanline(
        distance_m=np.asarray(values["distance"]),
        dip_deg=dip,
        dip_direction_deg=direction,
        trend_deg=geometry["trend_deg"],
        plunge_deg=geometry["plunge_deg"],
        length_m=length,
        trace_length_m=np.asarray(values["trace_length"]) if "trace_length" in values else None,
        termination=tuple(values["termination"]) if "termination" in values else None,
        start_xyz_m=geometry.get("start_xyz_m"),
        source=str(path),
    )
