"""Reading the files a subcommand is given: unreadable or unsuitable files are bad input (exit 2).

Every subcommand reads traces and polygon files the same way, so the messages are the same too:
they name the file and the flag, and what was expected.
"""

from __future__ import annotations

from .errors import InputError

__all__ = ["read_trace_file", "read_polygon_file"]


def read_trace_file(path, what: str = "trace"):
    """A :class:`~rockmass.dfn.TraceMap` from GeoJSON or CSV; a file that cannot be read is bad input."""
    from .dfn import read_traces

    try:
        return read_traces(path)
    except OSError as exc:
        raise InputError(f"{exc.filename or path}: cannot read the {what} file: "
                         f"{exc.strerror or exc}") from exc


def read_polygon_file(path, flag: str):
    """The polygon ring ``(k, 2)`` of a GeoJSON file given with ``flag`` (``--mask``, ``--area``, ...)."""
    ring = read_trace_file(path, flag).window_xy_m
    if ring is None:
        raise InputError(f"{path}: the {flag} file holds no polygon (a GeoJSON Polygon feature is "
                         "expected)")
    return ring
