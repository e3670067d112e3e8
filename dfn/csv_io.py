"""CSV trace files: read and write a :class:`~rockmass.dfn.TraceMap` as a table of segments or vertices.

Two layouts are accepted, recognised from the header (column names are case-insensitive,
surrounding whitespace is ignored, the layout columns may come in any order, and column names must
be unique regardless of case):

``segments``: ``x0,y0,x1,y1[,id][,attributes...]``
    Each row is one straight 2-vertex trace. A column named ``id`` (or ``trace_id``) gives the ids;
    without it the ids are 0..n-1.
``polylines``: ``trace_id,x,y[,attributes...]``
    Each row is one vertex; consecutive rows with the same ``trace_id`` form one trace, in row order.
    A trace's rows must be consecutive (a ``trace_id`` that reappears after another trace is an
    error), and every attribute column must hold the same text on all rows of a trace.

Other rules:

- Lines whose first non-blank character is ``#`` are comments. Before the header, the comments
  ``# frame: NAME`` and ``# crs: NAME`` set the map's frame and CRS (the writer emits them).
- Blank lines, and rows whose fields are all blank, are skipped.
- Coordinates must be finite numbers: an empty, non-numeric or non-finite value is an error naming
  the file, the line (1-based, as a text editor shows it) and the column.
- CSV has no types, so attribute columns are inferred: all ``true``/``false`` (any case) → bool; all
  integers → int64; all numbers, blanks allowed → float64 (blank or ``nan`` → NaN); anything else,
  including a column of blanks only → str, keeping the text verbatim. Ids are int64 when every id
  is an integer, else str (stripped). A string column whose values all look like numbers therefore
  reads back as numbers; use GeoJSON where string types must survive.
- The sampling window is not stored in CSV (it is not a per-trace or per-vertex quantity): keep it in
  a GeoJSON file. :func:`write_csv` warns when the map has a window.

Writing uses the polylines layout by default and writes floats with Python's shortest round-trip
repr, so coordinates read back identical; ``layout="segments"`` needs every trace to have exactly
2 vertices. The polylines layout needs unique ids, since it joins rows by ``trace_id``.
"""

from __future__ import annotations

import csv
import math
import os
import re
import warnings
from collections.abc import Iterator
from typing import IO

import numpy as np

from .atomic import atomic_open
from .frames import check_crs, default_frame, is_rockmass_local_crs
from .tracemap import TraceMap, _describe_traces, _plural, _require_trace_map, _resolve_frame

__all__ = ["read_csv", "write_csv"]

_SEGMENT_COLUMNS = ("x0", "y0", "x1", "y1")
_POLYLINE_COLUMNS = ("trace_id", "x", "y")
_ACCEPTED_HEADERS = (
    "expected the columns x0,y0,x1,y1 (segments: one straight trace per row) or trace_id,x,y "
    "(polylines: one vertex per row), optionally followed by attribute columns"
)
_LAYOUTS = ("polylines", "segments")
#: The key of a ``# frame: NAME`` / ``# crs: NAME`` comment; its value is the rest of the line,
#: stripped (:func:`_metadata`). No pattern spans the value: ``(.*?)\s*$`` took time quadratic in
#: the length of a line with long runs of spaces (a 100 kB line took a minute; issue 18).
_METADATA_KEY = re.compile(r"#\s*(frame|crs)\s*:", re.IGNORECASE)
_INTEGER = re.compile(r"[+-]?[0-9]+")
_INT64 = np.iinfo(np.int64)


# -- reading -------------------------------------------------------------------------------------


def read_csv(path: str | os.PathLike[str], *, frame: str | None = None) -> TraceMap:
    """Read traces from a CSV file in the segments or the polylines layout.

    Parameters
    ----------
    path : str or path-like
        A ``.csv`` file (UTF-8, a byte-order mark is allowed).
    frame : str, optional
        Frame name to use when the file has no ``# frame:`` comment (default then ``"face"``). If the
        file names a different frame, that is an error rather than a silent relabelling.

    Returns
    -------
    TraceMap
        Without a window (CSV does not store one).

    Raises
    ------
    ValueError
        A header matching neither layout (the message lists both), a bad coordinate (file, line and
        column named), a trace_id that reappears, an attribute that varies within a trace, a
        one-vertex trace, or a frame conflict.
    OSError
        If the file cannot be read.

    Notes
    -----
    The layouts and type rules are listed in the module docstring of :mod:`rockmass.dfn.csv_io`.
    """
    name = os.fspath(path)
    with open(path, newline="", encoding="utf-8-sig") as handle:
        try:
            return _Parser(name).parse(handle, frame)
        except UnicodeDecodeError as exc:
            raise ValueError(f"{name}: not UTF-8 text ({exc.reason} at byte {exc.start})") from exc


class _Parser:
    """One pass over a CSV file; tracks the physical line number for messages."""

    def __init__(self, name: str):
        self.name = name
        self.line = 0
        self.metadata: dict[str, str] = {}
        self.in_header = True

    def _lines(self, handle: IO[str]) -> Iterator[str]:
        in_quotes = False  # inside a quoted field that spans physical lines (RFC 4180)
        for number, text in enumerate(handle, start=1):
            self.line = number
            continues = in_quotes
            in_quotes ^= text.count('"') % 2 == 1  # an escaped quote ("") does not change parity
            if continues:
                yield text  # part of a quoted value, never a comment
                continue
            stripped = text.strip()
            if stripped.startswith("#"):
                match = _METADATA_KEY.match(stripped)
                if match and self.in_header:
                    key = match.group(1).lower()
                    if key in self.metadata:
                        raise ValueError(f"{self.name}: line {number}: a second '# {key}:' comment")
                    self.metadata[key] = stripped[match.end():].strip()
                continue
            yield text

    def parse(self, handle: IO[str], frame: str | None) -> TraceMap:
        rows = csv.reader(self._lines(handle))
        header: list[str] | None = None
        records = []
        try:
            for row in rows:
                if not any(field.strip() for field in row):
                    continue
                if header is None:
                    header, self.in_header = self._header(row), False
                elif len(row) != len(header):
                    raise ValueError(
                        f"{self.name}: line {self.line}: {_plural(len(row), 'field')}, but the header has {len(header)}"
                    )
                else:
                    records.append((self.line, row))
        except csv.Error as exc:
            raise ValueError(f"{self.name}: line {self.line}: {exc}") from exc
        if header is None:
            raise ValueError(f"{self.name}: no header line; {_ACCEPTED_HEADERS}")
        lower = [column.lower() for column in header]
        if all(c in lower for c in _SEGMENT_COLUMNS):
            polylines, columns = self._segments(header, lower, records)
        else:
            polylines, columns = self._polylines(header, lower, records)
        crs = self.metadata.get("crs") or None
        check_crs(crs, np.concatenate(polylines) if polylines else np.zeros((0, 2)), self.name)
        if is_rockmass_local_crs(crs):
            crs = None
        frame = _resolve_frame(self.metadata.get("frame"), frame, self.name, default_frame(crs))
        try:
            return TraceMap.from_polylines(polylines, columns, frame=frame, crs=crs)
        except ValueError as exc:
            raise ValueError(f"{self.name}: {exc}") from exc

    def _header(self, row: list[str]) -> list[str]:
        names = [field.strip() for field in row]
        lower = [n.lower() for n in names]
        where = f"{self.name}: line {self.line}: header"
        if "" in names:
            raise ValueError(f"{where}: column {names.index('') + 1} has no name")
        repeated = sorted({n for n in lower if lower.count(n) > 1})
        if repeated:
            raise ValueError(f"{where}: repeated column names {repeated} (names are case-insensitive)")
        is_segments = all(c in lower for c in _SEGMENT_COLUMNS)
        is_polylines = all(c in lower for c in _POLYLINE_COLUMNS)
        if is_segments == is_polylines:
            got = "both layouts" if is_segments else "neither layout"
            raise ValueError(f"{where} {','.join(names)!r} matches {got}; {_ACCEPTED_HEADERS}")
        return names

    def _number(self, text: str, line: int, column: str) -> float:
        where = f"{self.name}: line {line}, column {column!r}"
        stripped = text.strip()
        if not stripped:
            raise ValueError(f"{where}: empty value; expected a number (coordinate in metres)")
        try:
            value = float(stripped)
        except ValueError:
            raise ValueError(f"{where}: {text!r} is not a number") from None
        if not math.isfinite(value):
            raise ValueError(f"{where}: {text!r} is not finite; coordinates must be finite numbers")
        return value

    def _segments(self, names, lower, records):
        position = [lower.index(c) for c in _SEGMENT_COLUMNS]
        id_columns = [k for k, c in enumerate(lower) if c in ("id", "trace_id")]
        if len(id_columns) > 1:
            raise ValueError(f"{self.name}: header has both 'id' and 'trace_id'; give one id column")
        extra = [k for k in range(len(names)) if k not in position and k not in id_columns]
        polylines = []
        for line, row in records:
            x0, y0, x1, y1 = (self._number(row[k], line, names[k]) for k in position)
            polylines.append(((x0, y0), (x1, y1)))
        columns = {}
        if id_columns:
            columns["id"] = self._ids([(line, row[id_columns[0]]) for line, row in records], names[id_columns[0]])
        for k in extra:
            columns[names[k]] = _text_column([row[k] for _, row in records])
        return polylines, columns

    def _polylines(self, names, lower, records):
        id_k, x_k, y_k = (lower.index(c) for c in _POLYLINE_COLUMNS)
        if "id" in lower:
            raise ValueError(f"{self.name}: header has both 'trace_id' and 'id'; trace_id is the id column")
        extra = [k for k in range(len(names)) if k not in (id_k, x_k, y_k)]
        first_line: dict[str, int] = {}
        traces: list[tuple[str, int, list[str], list[tuple[float, float]]]] = []
        for line, row in records:
            tid = row[id_k].strip()
            if not tid:
                raise ValueError(f"{self.name}: line {line}, column {names[id_k]!r}: empty trace_id")
            if not traces or traces[-1][0] != tid:
                if tid in first_line:
                    raise ValueError(
                        f"{self.name}: line {line}: trace_id {tid!r} reappears after other traces (its rows "
                        f"started on line {first_line[tid]}); the rows of one trace must be consecutive"
                    )
                first_line[tid] = line
                traces.append((tid, line, [row[k] for k in extra], []))
            else:
                for k, value in zip(extra, traces[-1][2]):
                    if row[k] != value:
                        raise ValueError(
                            f"{self.name}: line {line}, column {names[k]!r}: {row[k]!r} differs from {value!r} "
                            f"on line {traces[-1][1]} of trace {tid!r}; attributes must be constant within a trace"
                        )
            traces[-1][3].append((self._number(row[x_k], line, names[x_k]), self._number(row[y_k], line, names[y_k])))
        for tid, line, _, vertices in traces:
            if len(vertices) < 2:
                raise ValueError(
                    f"{self.name}: line {line}: trace_id {tid!r} has 1 vertex; a trace needs at least 2 "
                    "(one row per vertex)"
                )
        columns = {"id": self._ids([(t[1], t[0]) for t in traces], names[id_k])}
        for j, k in enumerate(extra):
            columns[names[k]] = _text_column([t[2][j] for t in traces])
        return [t[3] for t in traces], columns

    def _ids(self, values: list[tuple[int, str]], column: str) -> np.ndarray:
        texts = [text.strip() for _, text in values]
        for (line, _), text in zip(values, texts):
            if not text:
                raise ValueError(f"{self.name}: line {line}, column {column!r}: empty id")
        integers = _as_int64(texts)
        return integers if integers is not None else np.array(texts, dtype=str)


def _as_int64(texts: list[str]) -> np.ndarray | None:
    """int64 array if every (stripped) text is a decimal integer in range, else None."""
    if not all(_INTEGER.fullmatch(t) for t in texts):
        return None
    values = [int(t) for t in texts]
    if values and not (_INT64.min <= min(values) and max(values) <= _INT64.max):
        return None
    return np.array(values, dtype=np.int64)


def _text_column(texts: list[str]) -> np.ndarray:
    """One attribute column from CSV text, by the type rules in the module docstring."""
    stripped = [t.strip() for t in texts]
    filled = [s for s in stripped if s]
    if filled and len(filled) == len(stripped):
        if all(s.lower() in ("true", "false") for s in stripped):
            return np.array([s.lower() == "true" for s in stripped], dtype=bool)
        integers = _as_int64(stripped)
        if integers is not None:
            return integers
    if filled:
        try:
            return np.array([float(s) if s else np.nan for s in stripped], dtype=np.float64)
        except ValueError:
            pass
    return np.array(texts, dtype=str)


# -- writing -------------------------------------------------------------------------------------


def _format_column(column: np.ndarray) -> list[str]:
    """Text of each value: full-precision floats (repr), 'true'/'false' for bools."""
    if column.dtype.kind == "b":
        return ["true" if v else "false" for v in column.tolist()]
    if column.dtype.kind == "f":
        return [repr(v) for v in column.tolist()]
    return [str(v) for v in column.tolist()]


def write_csv(trace_map: TraceMap, path: str | os.PathLike[str], *, layout: str = "polylines") -> None:
    """Write a trace map as CSV, atomically.

    Parameters
    ----------
    trace_map : TraceMap
        The map to write; it is not modified.
    path : str or path-like
        Destination; replaced only once the whole file is written.
    layout : {"polylines", "segments"}, default "polylines"
        ``polylines``: header ``trace_id,x,y,<attributes>``, one row per vertex. ``segments``: header
        ``x0,y0,x1,y1,id,<attributes>``, one row per trace; every trace must have exactly 2 vertices.

    Raises
    ------
    ValueError
        Unknown layout; ``segments`` with a trace of more than 2 vertices, or ``polylines`` with
        repeated ids (both name the traces); an attribute name that clashes with a layout column,
        differs from another only by case, or has surrounding whitespace.
    OSError
        If the file cannot be written.

    Warns
    -----
    UserWarning
        When the map has a sampling window, which CSV does not store.

    Notes
    -----
    Comment lines ``# frame: ...`` (and ``# crs: ...``) precede the header so the frame survives
    a round trip. Floats are written with ``repr`` (NaN as ``nan``), so coordinates read back identical.
    """
    _require_trace_map(trace_map)
    name = os.fspath(path)
    if layout not in _LAYOUTS:
        raise ValueError(f"layout must be one of {list(_LAYOUTS)}, got {layout!r}")
    ids = trace_map.attributes["id"]
    extra = [key for key in trace_map.attributes if key != "id"]
    reserved = {"id", *_SEGMENT_COLUMNS, *_POLYLINE_COLUMNS}  # either set would change the detected layout
    lowered = [key.lower() for key in extra]
    for key in extra:
        if key.lower() in reserved or lowered.count(key.lower()) > 1 or key != key.strip():
            raise ValueError(
                f"{name}: attribute name {key!r} cannot be a CSV column (it clashes "
                f"with a layout column {sorted(reserved)}, with another name up to case, or has surrounding spaces)"
            )
    for label, value in (("frame", trace_map.frame), ("crs", trace_map.crs)):
        if value is not None and ("\n" in value or "\r" in value or value != value.strip()):
            raise ValueError(f"{name}: {label} {value!r} cannot be stored in a '# {label}:' comment line")
    counts = np.diff(trace_map.offsets)
    if layout == "segments":
        longer = np.flatnonzero(counts != 2)
        if longer.size:
            raise ValueError(
                f"{name}: layout='segments' needs every trace to have exactly 2 vertices; "
                f"{_plural(longer.size, 'trace', 'has')} more: {_describe_traces(longer, ids)}; use layout='polylines'"
            )
    else:
        unique, first, seen = np.unique(ids, return_index=True, return_counts=True)
        if unique.size < ids.size:
            repeated = np.sort(first[seen > 1])
            raise ValueError(
                f"{name}: layout='polylines' joins rows by trace_id, so ids must be unique; repeated "
                f"{_describe_traces(repeated, ids)}; give unique ids or use layout='segments' or GeoJSON"
            )
    if trace_map.window_xy_m is not None:
        warnings.warn(
            f"{name}: CSV does not store the sampling window; write GeoJSON to keep it", UserWarning, stacklevel=2
        )
    id_text = _format_column(ids)
    attribute_text = [_format_column(trace_map.attributes[key]) for key in extra]
    with atomic_open(path, newline="") as handle:
        # CRLF line ends (RFC 4180): the csv module then quotes any field holding a \r or \n
        handle.write(f"# frame: {trace_map.frame}\r\n")
        if trace_map.crs is not None:
            handle.write(f"# crs: {trace_map.crs}\r\n")
        plain = csv.writer(handle, lineterminator="\r\n")
        quoted = csv.writer(handle, lineterminator="\r\n", quoting=csv.QUOTE_ALL)
        if layout == "segments":
            plain.writerow([*_SEGMENT_COLUMNS, "id", *extra])
            for i, (x0, y0, x1, y1) in enumerate(trace_map.segments().tolist()):
                plain.writerow([repr(x0), repr(y0), repr(x1), repr(y1), id_text[i], *(t[i] for t in attribute_text)])
            return
        plain.writerow([*_POLYLINE_COLUMNS, *extra])
        xy, offsets = trace_map.xy_m.tolist(), trace_map.offsets.tolist()
        for i in range(trace_map.n_traces):
            attrs = [t[i] for t in attribute_text]
            # a first field starting with '#' would read back as a comment line: quote that row
            writer = quoted if id_text[i].lstrip().startswith("#") else plain
            for x, y in xy[offsets[i] : offsets[i + 1]]:
                writer.writerow([id_text[i], repr(x), repr(y), *attrs])
