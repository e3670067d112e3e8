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
"""

from .csv_io import read_csv, write_csv
from .geojson_io import read_geojson, write_geojson
from .traceio import read_traces, write_traces
from .tracemap import TraceMap

__all__ = [
    "TraceMap",
    "read_traces",
    "write_traces",
    "read_geojson",
    "write_geojson",
    "read_csv",
    "write_csv",
]
