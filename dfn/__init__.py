"""The fracture data model and its files: trace maps, readers and writers.

Public names
------------
:class:`TraceMap`
    Joint traces as polylines in metres in a named frame, with per-trace attributes and the sampling
    window polygon (:mod:`rockmass.dfn.tracemap`).
:func:`read_traces`, :func:`write_traces`
    GeoJSON or CSV by suffix (:mod:`rockmass.dfn.traceio`).
:func:`read_geojson`, :func:`write_geojson`, :func:`read_csv`, :func:`write_csv`
    The explicit readers and writers (:mod:`rockmass.dfn.geojson_io`, :mod:`rockmass.dfn.csv_io`).

``rockmass.dfn`` depends on numpy and shapely only: it never imports the pipeline package
(``rockmass`` top-level modules) nor numba, matplotlib, OpenCV or scikit-image at import time.
The public names load on first use (PEP 562), so importing the package, or its standard-library-only
module :mod:`rockmass.dfn._atomic` (the atomic file writes that every rockmass writer shares), does
not load numpy or shapely either.
"""

from __future__ import annotations

import importlib as _importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .csv_io import read_csv, write_csv
    from .geojson_io import read_geojson, write_geojson
    from .traceio import read_traces, write_traces
    from .tracemap import TraceMap

#: Public name -> the module that defines it.
_SOURCES = {
    "TraceMap": "tracemap",
    "read_traces": "traceio",
    "write_traces": "traceio",
    "read_geojson": "geojson_io",
    "write_geojson": "geojson_io",
    "read_csv": "csv_io",
    "write_csv": "csv_io",
}

__all__ = list(_SOURCES)


def __getattr__(name: str) -> object:
    """Import a public name's module on first access and cache the name here."""
    source = _SOURCES.get(name)
    if source is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_importlib.import_module(f".{source}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
