"""Reading the files a subcommand is given: unreadable or unsuitable files are bad input (exit 2).

Every subcommand reads traces and polygon files the same way, so the messages are the same too:
they name the file and the flag, and what was expected.

Zero-length traces (every vertex of the feature the same point) are dropped with a warning that
names the file, counts them and names them (:func:`drop_zero_length`): a trace of no length is a
digitising slip (a double click, a snapped end point), not a joint seen on the face. A geologist
expects it neither to count towards P20 and the number of traces nor to stop the analysis of a map of
thousands of good traces; dropping it silently would hide the slip, so the warning goes to stderr
and the count into the outputs (``summary.json`` ``input.dropped_zero_length`` of ``rockmass
traces``).
"""

from __future__ import annotations

from .errors import InputError

__all__ = ["read_trace_file", "read_trace_map", "drop_zero_length", "warn", "read_polygon_file"]

#: Most trace indices and ids a warning or an output lists (the count is always whole).
MAX_NAMED = 20


def warn(text: str) -> None:
    """Print a warning on stderr (``rockmass: warning: ...``)."""
    import sys

    print(f"rockmass: warning: {text}", file=sys.stderr)


def drop_zero_length(trace_map, path):
    """The map without its zero-length traces, and what was dropped.

    Returns
    -------
    (TraceMap, dict)
        The map (the same object when nothing was dropped) and ``{"count", "trace_indices",
        "ids", "text"}``: how many traces were dropped, the first :data:`MAX_NAMED` of their
        0-based positions among the file's traces and of their ids, and the warning text naming
        ``path`` (empty when nothing was dropped).
    """
    import numpy as np

    zero = trace_map.degenerate_traces() if trace_map.n_traces else np.zeros(0, bool)
    where = np.flatnonzero(zero)
    if not where.size:
        return trace_map, {"count": 0, "trace_indices": [], "ids": [], "text": ""}
    indices = where[:MAX_NAMED].tolist()
    ids = trace_map.attributes["id"][where[:MAX_NAMED]].tolist()
    more = f" and {where.size - len(indices)} more" if where.size > len(indices) else ""
    names = ""
    if "name" in trace_map.attributes:  # the feature names a user digitised, when the file has them
        names = f", names {[str(v) for v in trace_map.attributes['name'][where[:MAX_NAMED]]]}{more}"
    text = (f"{path}: dropped {where.size} zero-length trace{'s' if where.size > 1 else ''} "
            f"(every point the same: a digitising slip?) of {trace_map.n_traces}, not counted: "
            f"traces {indices}{more} (0-based, in the file's order), ids {ids}{more}{names}")
    return trace_map.subset(~zero), {"count": int(where.size), "trace_indices": indices,
                                     "ids": ids, "text": text}


def read_trace_map(path, what: str = "trace", layer: str | None = None):
    """``(TraceMap, dropped)`` from GeoJSON, CSV, GeoPackage or Shapefile (its traces ``layer``)
    without its zero-length traces (:func:`drop_zero_length`); a file that cannot be read, or a
    GeoPackage / Shapefile without the optional pyogrio, is bad input."""
    from .dfn import read_traces

    try:
        trace_map = read_traces(path, layer=layer)
    except ImportError as exc:  # the message says: pip install 'rockmass[gis]'
        raise InputError(f"{path}: cannot read the {what} file: {exc}") from exc
    except OSError as exc:
        raise InputError(f"{exc.filename or path}: cannot read the {what} file: "
                         f"{exc.strerror or exc}") from exc
    return drop_zero_length(trace_map, path)


def read_trace_file(path, what: str = "trace", *, quiet: bool = False):
    """A :class:`~rockmass.dfn.TraceMap` from GeoJSON or CSV without its zero-length traces,
    warned about on stderr unless ``quiet``; a file that cannot be read is bad input."""
    trace_map, dropped = read_trace_map(path, what)
    if dropped["count"] and not quiet:
        warn(dropped["text"])
    return trace_map


def read_polygon_file(path, flag: str):
    """The polygon ring ``(k, 2)`` of a GeoJSON file given with ``flag`` (``--mask``, ``--area``, ...)."""
    ring = read_trace_file(path, flag, quiet=True).window_xy_m
    if ring is None:
        raise InputError(f"{path}: the {flag} file holds no polygon (a GeoJSON Polygon feature is "
                         "expected)")
    return ring
