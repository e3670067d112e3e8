"""Trace files by suffix: :func:`read_traces` and :func:`write_traces`.

This module owns the choice of format from a file's suffix; the formats themselves live in
:mod:`rockmass.dfn.geojson_io`, :mod:`rockmass.dfn.csv_io` and :mod:`rockmass.dfn.gis_io`, whose module
docstrings state the rules each reader follows. In short:

=====================  ==========  ====================================================================
suffix                 format      holds
=====================  ==========  ====================================================================
``.geojson``, ``.json`` GeoJSON    LineString / MultiLineString traces with properties, the window
                                   Polygon (``"role": "window"``), ``frame`` and ``crs`` members
``.csv``               CSV         segments ``x0,y0,x1,y1[,id,...]`` or polylines ``trace_id,x,y[,...]``;
                                   ``# frame:`` / ``# crs:`` comments; no window
``.gpkg``              GeoPackage  a line layer of traces and a polygon layer of the area (``layer=``
                                   picks the traces layer of several); needs pyogrio
                                   (``pip install 'rockmass[gis]'``)
``.shp``               Shapefile   lines (traces) or one polygon (an area file); needs pyogrio
=====================  ==========  ====================================================================

Suffixes are matched case-insensitively. Every writer is atomic (temporary file in the same folder,
fsync, rename), so an interrupted or failed write leaves any previous file untouched.
Errors: ``ValueError`` for bad content (naming the file, the feature or line, and the field),
``TypeError`` for a wrong argument type, and ``OSError`` (unchanged) for unreadable or unwritable files.
"""

from __future__ import annotations

import os
from pathlib import Path

from .csv_io import read_csv, write_csv
from .geojson_io import read_geojson, write_geojson
from .gis_io import GIS_SUFFIXES, read_gis, write_gis
from .tracemap import TraceMap, _require_trace_map

__all__ = ["read_traces", "write_traces"]

_FORMATS = {".geojson": "geojson", ".json": "geojson", ".csv": "csv", **dict.fromkeys(GIS_SUFFIXES, "gis")}
_ACCEPTED = ".geojson or .json (GeoJSON), .csv (CSV), .gpkg (GeoPackage), .shp (Shapefile)"


def _format_of(path: str | os.PathLike[str], action: str) -> str:
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or path-like, got {type(path).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix not in _FORMATS:
        shown = repr(suffix) if suffix else "no suffix"
        raise ValueError(
            f"{os.fspath(path)}: cannot {action} traces from a file with {shown}; accepted suffixes: {_ACCEPTED}"
        )
    return _FORMATS[suffix]


def read_traces(path: str | os.PathLike[str], *, frame: str | None = None, layer: str | None = None) -> TraceMap:
    """Read a trace map from a GeoJSON, CSV, GeoPackage or Shapefile, chosen by the file's suffix.

    Parameters
    ----------
    path : str or path-like
        ``.geojson`` / ``.json`` (read with :func:`read_geojson`), ``.csv`` (:func:`read_csv`),
        ``.gpkg`` or ``.shp`` (:func:`~rockmass.dfn.gis_io.read_gis`).
    frame : str, optional
        Frame name for files that do not name one; a file naming a different frame is an error.
        Default None (the file's frame, else ``"face"``).
    layer : str, optional
        The traces layer of a GeoPackage with several line layers; an error for other formats.
        Default None.

    Returns
    -------
    TraceMap

    Raises
    ------
    ValueError
        Unknown suffix (the message lists the accepted ones) or bad file content.
    ImportError
        A GeoPackage or Shapefile without pyogrio installed.
    OSError
        If the file cannot be read.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "traces.csv"
    >>> _ = path.write_text("x0,y0,x1,y1,set\\n0,0,3,4,1\\n0,0,0,2,2\\n")
    >>> tm = read_traces(path)
    >>> tm.lengths_m(), tm.attributes["set"]
    (array([5., 2.]), array([1, 2]))
    """
    kind = _format_of(path, "read")
    if kind == "gis":
        return read_gis(path, frame=frame, layer=layer)
    if layer is not None:
        raise ValueError(f"{os.fspath(path)}: a layer ({layer!r}; --layer on the command line) picks the "
                         f"traces of a GeoPackage (.gpkg); a {Path(path).suffix} file has no layers")
    if kind == "geojson":
        return read_geojson(path, frame=frame)
    return read_csv(path, frame=frame)


def write_traces(trace_map: TraceMap, path: str | os.PathLike[str]) -> None:
    """Write a trace map to a GeoJSON, CSV, GeoPackage or Shapefile (chosen by suffix), atomically.

    Parameters
    ----------
    trace_map : TraceMap
        The map to write; it is not modified.
    path : str or path-like
        ``.geojson`` / ``.json`` (:func:`write_geojson`), ``.csv`` (:func:`write_csv`, polylines
        layout; call :func:`write_csv` directly for ``layout="segments"``), ``.gpkg`` / ``.shp``
        (:func:`~rockmass.dfn.gis_io.write_gis`: the ``traces`` and ``area`` layers; call it with a
        ``network`` for the ``nodes`` and ``branches`` layers too).

    Raises
    ------
    ValueError
        Unknown suffix, or content the format cannot hold (see the writers).
    TypeError
        If ``trace_map`` is not a :class:`TraceMap`.
    OSError
        If the file cannot be written; a previous file at ``path`` is left as it was.

    Warns
    -----
    UserWarning
        Writing CSV for a map that has a sampling window (CSV does not store it).
    """
    _require_trace_map(trace_map)
    kind = _format_of(path, "write")
    if kind == "geojson":
        write_geojson(trace_map, path)
    elif kind == "gis":
        write_gis(trace_map, path)
    else:
        write_csv(trace_map, path)
