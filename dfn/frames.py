"""Frames of trace maps: coordinate reference systems and the convention of trace angles.

A trace map's coordinates are metres in a named frame (:attr:`TraceMap.frame`, docs/fractures.md
§1.2). This module owns the three rules that follow from the frame (issue 19):

Coordinate reference systems
----------------------------
:func:`crs_kind` classifies a CRS name as ``"geographic"`` (longitude / latitude in degrees:
``OGC:CRS84``, ``EPSG:4326``, a ``GEOGCS`` WKT, ``+proj=longlat``, ...), ``"projected"``,
``"local"`` (an engineering frame: ``LOCAL_CS`` / ``ENGCRS`` WKT) or ``"unknown"``. pyproj is used
when it is installed; without it the common forms are recognised by rule, and an EPSG code in the
4000-4999 block (where EPSG keeps its geographic CRSs, and a few projected ones) that is not in the
built-in list is ``"geographic?"``: geographic only when every coordinate also looks like degrees.
:func:`check_crs` refuses geographic coordinates (lengths and areas in degrees are meaningless),
saying how to reproject. A GeoJSON file with no ``crs`` member is, by RFC 7946, WGS 84
longitude / latitude: such a file is refused when its coordinates look like degrees *and* the whole
map spans less than :data:`DEGREE_EXTENT` (0.1; an outcrop in degrees spans 0.001, a map in metres
of less than 10 cm is not a trace map); otherwise it is read as metres in a local frame, as rockmass
always did.

Face frames as a local CRS
--------------------------
A face photograph's frame (u right, v up, metres) is no place on Earth. Writers name it with
:func:`local_crs_wkt`, a WKT ``LOCAL_CS`` that GDAL and QGIS read as a local engineering CRS, so a
GIS does not take a face map for WGS 84 (which it assumes for GeoJSON without ``crs``). Readers
recognise it (:func:`is_rockmass_local_crs`) and give the map no CRS again.

Angle conventions
-----------------
Inside rockmass a trace angle θ is counter-clockwise from +x (+u on a face), 0-180°
(docs/fractures.md §1.4). What users read depends on the frame (:func:`angle_convention`):

=============  ===========================================================================
convention     outputs
=============  ===========================================================================
``azimuth``    map frames (``frame == "map"``: easting x, northing y): azimuth clockwise
               from North, 0-180° for undirected traces, as fractopo and geologists read
               it: az = (90° − θ) mod 180° (:func:`to_convention`)
``face``       face photographs and sections (``"face"``, ``"plane"``, any other frame):
               counter-clockwise from +u (the face's right), 0-180°
=============  ===========================================================================
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

__all__ = ["ANGLE_CONVENTIONS", "DEGREE_EXTENT", "MAP_FRAME", "angle_convention", "check_crs",
           "crs_kind", "default_frame", "is_rockmass_local_crs", "local_crs_wkt", "to_convention"]

#: The frame name of a map in a GIS CRS (x easting, y northing).
MAP_FRAME = "map"

#: Each angle convention and what it means, as every output that carries an angle states it.
ANGLE_CONVENTIONS = {
    "azimuth": "azimuth in degrees clockwise from North (+y), 0-180 for undirected traces",
    "face": "degrees counter-clockwise from +u (the face's right, or the frame's +x), 0-180",
}

#: A file without a CRS whose coordinates look like degrees is refused when the map spans less
#: than this (in its units): 0.1° is about 11 km, 0.1 m is smaller than any trace map in metres.
DEGREE_EXTENT = 0.1

_LOCAL_PREFIX = 'LOCAL_CS["rockmass '

#: EPSG codes of common geographic (and geocentric) CRSs, recognised without pyproj; other codes
#: of the 4000-4999 block are "geographic?" (decided by the coordinates).
_GEOGRAPHIC_EPSG = frozenset({4326, 4979, 4258, 4937, 4269, 4267, 4230, 4283, 4617, 4490, 4612, 6668,
                              7844, 4148, 4167, 4978, 4936, 4328})
_EPSG_CODE = re.compile(r"EPSG(?::+|:[\d.]*:|/\d+/)(\d+)$")
_GEOGRAPHIC_NAMES = {"WGS84", "WGS 84", "NAD83", "NAD27", "ETRS89", "GRS80", "CRS84", "CRS83", "CRS27"}


def local_crs_wkt(frame: str) -> str:
    """WKT ``LOCAL_CS`` naming the local engineering frame ``frame`` (u right, v up, metres).

    Examples
    --------
    >>> local_crs_wkt("face")[:46]
    'LOCAL_CS["rockmass face frame: u right, v up ('
    """
    label = frame.replace('"', "'")
    return (f'{_LOCAL_PREFIX}{label} frame: u right, v up (metres), not georeferenced",'
            f'LOCAL_DATUM["rockmass {label}",0],UNIT["metre",1],AXIS["u",EAST],AXIS["v",NORTH]]')


def is_rockmass_local_crs(crs: str | None) -> bool:
    """True for a CRS written by :func:`local_crs_wkt`."""
    return isinstance(crs, str) and crs.strip().startswith(_LOCAL_PREFIX)


def _pyproj_kind(crs: str) -> str | None:
    try:
        import pyproj
    except ImportError:
        return None
    try:
        parsed = pyproj.CRS.from_user_input(crs)
    except Exception:  # noqa: BLE001 - pyproj's errors vary by version; fall back to the rules
        return None
    if parsed.is_geographic or parsed.is_geocentric:
        return "geographic"
    if parsed.is_projected:
        return "projected"
    if getattr(parsed, "is_engineering", False):
        return "local"
    return None


def crs_kind(crs: str | None) -> str:
    """Classify a CRS name: ``"geographic"``, ``"geographic?"``, ``"projected"``, ``"local"``,
    ``"unknown"`` or ``"none"`` (no CRS).

    ``"geographic?"``: an EPSG code of the 4000-4999 block that is not in the built-in list (without
    pyproj); :func:`check_crs` then looks at the coordinates.

    Examples
    --------
    >>> [crs_kind(c) for c in ("urn:ogc:def:crs:OGC:1.3:CRS84", "EPSG:4326", "EPSG:32633",
    ...                        "urn:ogc:def:crs:EPSG::3067", local_crs_wkt("face"), None)]
    ['geographic', 'geographic', 'projected', 'projected', 'local', 'none']
    """
    if crs is None:
        return "none"
    text = crs.strip()
    upper = text.upper()
    if upper.startswith(("LOCAL_CS", "ENGCRS", "ENGINEERINGCRS")):
        return "local"
    kind = _pyproj_kind(text)
    if kind is not None:
        return kind
    if upper.replace(" ", "") in {n.replace(" ", "") for n in _GEOGRAPHIC_NAMES} or "CRS84" in upper \
            or "CRS83" in upper or "CRS27" in upper:
        return "geographic"
    if upper.startswith(("GEOGCS", "GEOGCRS", "GEOGRAPHICCRS", "GEOCCS")):
        return "geographic"
    if upper.startswith("GEODCRS") or upper.startswith("GEODETICCRS"):
        return "geographic"  # ellipsoidal (lon/lat) or geocentric: neither is metres on a map
    if upper.startswith(("PROJCS", "PROJCRS", "PROJECTEDCRS")):
        return "projected"
    if upper.startswith(("COMPD_CS", "COMPOUNDCRS")):
        return "projected" if ("PROJCS" in upper or "PROJCRS" in upper) else "geographic"
    if "+PROJ=" in upper:
        return "geographic" if re.search(r"\+PROJ=(LONGLAT|LATLONG|LONLAT|LATLON)\b", upper) else "projected"
    match = _EPSG_CODE.search(upper)
    if match:
        code = int(match.group(1))
        if code in _GEOGRAPHIC_EPSG:
            return "geographic"
        if 4000 <= code <= 4999:
            return "geographic?"
        return "projected"
    return "unknown"


def _look_like_degrees(xy: np.ndarray) -> bool:
    """Every coordinate within longitude [-180, 180] and latitude [-90, 90]."""
    return bool(xy.size) and bool(np.all(np.abs(xy[:, 0]) <= 180.0) and np.all(np.abs(xy[:, 1]) <= 90.0))


def check_crs(crs: str | None, xy: Any, name: str, *, rfc7946_default: bool = False) -> str:
    """Refuse geographic coordinates; return the CRS's kind (see :func:`crs_kind`).

    Parameters
    ----------
    crs : str or None
        The file's CRS name.
    xy : (n, 2) array_like of float
        Every coordinate of the file (traces and window).
    name : str
        The file, for the message.
    rfc7946_default : bool, default False
        The file is GeoJSON with neither a ``crs`` nor a ``frame`` member: by RFC 7946 its
        coordinates are WGS 84 longitude / latitude. It is refused when they look like degrees and
        span less than :data:`DEGREE_EXTENT`.

    Raises
    ------
    ValueError
        Geographic coordinates; the message names the file and the CRS and says how to reproject.
    """
    kind = crs_kind(crs)
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    degrees = _look_like_degrees(xy)
    how = ("trace statistics need coordinates in metres: reproject the file to a projected CRS "
           "(e.g. the local UTM zone) first, e.g. `ogr2ogr -t_srs EPSG:32633 out.geojson in.geojson` "
           "or in QGIS Export > Save Features As... with a projected CRS")
    if kind == "geographic" or (kind == "geographic?" and degrees):
        raise ValueError(f"{name}: crs {crs!r} is geographic (longitude/latitude in degrees); {how}")
    if kind == "none" and rfc7946_default and degrees:
        span = float(np.max(xy.max(axis=0) - xy.min(axis=0)))
        if span < DEGREE_EXTENT:
            raise ValueError(
                f"{name}: the file names no crs, so by RFC 7946 its coordinates are WGS 84 "
                f"longitude/latitude, and they look like it (the map spans {span:.3g} units); {how}. "
                'If they are metres in a local frame, name the frame: add "frame": "face" (or '
                '"map" for a North-up map) to the FeatureCollection')
    return kind


def default_frame(crs: str | None) -> str:
    """The frame of a file that names none: ``"map"`` when it has a GIS CRS (geographic ones are
    refused before), ``"face"`` otherwise (no CRS, or rockmass's own local CRS)."""
    if crs is None or is_rockmass_local_crs(crs):
        return "face"
    return MAP_FRAME


def angle_convention(frame: str) -> str:
    """The convention of trace angles in outputs: ``"azimuth"`` for a map frame, else ``"face"``.

    >>> angle_convention("map"), angle_convention("face"), angle_convention("plane")
    ('azimuth', 'face', 'face')
    """
    return "azimuth" if frame == MAP_FRAME else "face"


def to_convention(angles_deg: Any, convention: str) -> np.ndarray:
    """Angles counter-clockwise from +x (0-180°) in ``convention``; NaN stays NaN.

    ``"azimuth"``: az = (90° − θ) mod 180°, clockwise from North (+y); ``"face"``: unchanged.

    Examples
    --------
    >>> to_convention([0.0, 45.0, 90.0, 135.0], "azimuth").tolist()
    [90.0, 45.0, 0.0, 135.0]
    """
    angles = np.asarray(angles_deg, dtype=np.float64)
    if convention == "face":
        return angles.copy()
    if convention != "azimuth":
        raise ValueError(f"convention must be one of {', '.join(map(repr, ANGLE_CONVENTIONS))}, got {convention!r}")
    out = np.mod(90.0 - angles, 180.0)
    return np.where(out >= 180.0, 0.0, out)  # rounding of values just below 180
