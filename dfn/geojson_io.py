"""GeoJSON trace files: read and write a :class:`~rockmass.dfn.TraceMap` as a FeatureCollection.

This is the format fractopo and QGIS users already have. The rules below are the contract; the tests
in ``tests/dfn/test_traceio.py`` check each one.

Reading
-------
- The file holds a FeatureCollection, a single Feature or a bare geometry (RFC 7946).
- A **LineString** feature is one trace. A **MultiLineString** feature is merged with
  :func:`shapely.line_merge` into one trace when its parts join end to end (in either direction) into
  a single line; the merged trace's vertex order is GEOS's. Otherwise each part becomes its own trace
  carrying the feature's properties plus ``part``, the part's 0-based index in the feature's
  ``coordinates``; when any feature is split, traces that came whole get ``part = -1``.
- A **Polygon** feature, or a feature whose properties have ``"role": "window"`` (a Polygon or a
  closed LineString), is the sampling window. Only its exterior ring is read (holes are an error), its
  properties are not kept, and a second window is an error.
- Every other geometry (Point, MultiPoint, MultiPolygon, GeometryCollection) and a null geometry is
  an error naming the feature. None is ignored: a stray point layer (fractopo's nodes, say) or an
  undigitised feature usually means the wrong file or an unfinished one, and dropping features
  silently would change the intensities computed downstream.
- Positions keep x and y; a z (or m) value is dropped. ``NaN`` and ``Infinity`` (which Python's json
  module accepts), a coordinate beyond ±10¹² m (:data:`rockmass.dfn.tracemap.MAX_COORDINATE_M`:
  a typo or a unit slip) and a ``true`` / ``false`` where a number belongs are reported with the
  feature, as is a trace with fewer than 2 vertices.
- Properties become attribute columns (union of keys, in order of first appearance). A column whose
  values are all booleans is bool; all integers, int64; numbers, float64. A missing or null value is
  NaN in a numeric column (so an integer or bool column with gaps becomes float64) and '' in a string
  column. A column mixing types (or holding lists/objects) is str, non-strings written as JSON text.
- ``id`` comes from ``properties.id``, else from the feature's own ``id`` member; integer-valued ids
  give an int64 column (missing: -1), any other id a str column (missing: ''). Without any id the
  ids are the trace indices 0..n-1.
- The top-level foreign members ``"frame"`` (a string) and ``"crs"`` (a string, or the legacy
  ``{"type": "name", "properties": {"name": ...}}`` / ``{"type": "EPSG", "properties": {"code": ...}}``
  objects) are read; the name is kept verbatim. A geographic CRS (``OGC:CRS84``, ``EPSG:4326``, any
  longitude / latitude) is an error saying how to reproject, and so is a file without ``crs`` and
  ``frame`` whose coordinates look like degrees over less than 0.1 unit (RFC 7946's WGS 84 default;
  :func:`rockmass.dfn.frames.check_crs`). The local CRS the writer names a face frame with is
  recognised and gives the map no CRS. A file that names no frame is in frame ``"map"`` when it has
  a (projected) CRS, else ``"face"``; the frame decides the angle convention of the statistics
  (:func:`rockmass.dfn.frames.angle_convention`).

Writing
-------
One LineString feature per trace with its attributes as properties (``id`` first; NaN written as
null, since JSON has no NaN), then the window as a Polygon feature with ``"role": "window"``, with
``frame``, ``angle_convention`` (what an angle attribute such as ``angle_deg`` means in this frame,
:func:`rockmass.dfn.frames.angle_convention`; ignored on reading) and ``crs`` (legacy named form,
which GDAL/QGIS read) as top-level members. A map without a
CRS gets the WKT ``LOCAL_CS`` of its frame (:func:`rockmass.dfn.frames.local_crs_wkt`) as ``crs``, so
GIS tools read it as a local engineering frame, not as WGS 84. Coordinates are
written with Python's shortest round-trip float repr, so reading the file back gives identical
float64 values. One feature per line keeps the file diff-friendly.

Error messages name the file, the feature index (0-based, as in ``features``) with its id, and the
field, e.g. ``faces.geojson: feature 12 (id=T13): coordinates contain NaN/Infinity at positions [3]``.
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np
import shapely

from .atomic import atomic_open
from .frames import angle_convention, check_crs, default_frame, is_rockmass_local_crs, local_crs_wkt
from .tracemap import (_MAX_LISTED, MAX_COORDINATE_M, TraceMap, _as_window, _beyond_range, _describe_traces,
                       _require_trace_map, _resolve_frame)

__all__ = ["read_geojson", "write_geojson"]

_GEOMETRY_TYPES = (
    "Point",
    "MultiPoint",
    "LineString",
    "MultiLineString",
    "Polygon",
    "MultiPolygon",
    "GeometryCollection",
)
_MISSING = None  # absent keys and JSON null are both "missing"
_INT64 = np.iinfo(np.int64)


# -- reading -------------------------------------------------------------------------------------


def read_geojson(path: str | os.PathLike[str], *, frame: str | None = None) -> TraceMap:
    """Read traces (and the sampling window) from a GeoJSON file.

    Parameters
    ----------
    path : str or path-like
        A ``.geojson`` / ``.json`` file (UTF-8).
    frame : str, optional
        Frame name to use when the file has no ``"frame"`` member (default then ``"face"``). If the
        file names a different frame, that is an error rather than a silent relabelling.

    Returns
    -------
    TraceMap

    Raises
    ------
    ValueError
        Invalid JSON (with line and column), a feature that is not a trace or window, bad
        coordinates, two windows, or a frame conflict; the message names the file and the feature.
    OSError
        If the file cannot be read.

    Notes
    -----
    The reading rules (MultiLineString merging and splitting, windows, attribute types, ids) are
    listed in the module docstring of :mod:`rockmass.dfn.geojson_io`.
    """
    name = os.fspath(path)
    doc = _load_json(path, name)
    features = _feature_list(doc, name)
    crs = _read_crs(doc.get("crs"), name)
    file_frame = _read_frame(doc.get("frame"), name)
    polylines: list[np.ndarray] = []
    records: list[dict[str, Any]] = []
    window, window_index, split_any = None, None, False
    for index, feature in enumerate(features):
        where = _where(name, index, feature)
        geometry, props = _unpack_feature(feature, where)
        kind = geometry["type"]
        if kind == "Polygon" or props.get("role") == "window":
            if window is not None:
                raise ValueError(
                    f"{where}: a second window polygon (feature {window_index} is already the window); "
                    "a trace map has one sampling window"
                )
            window, window_index = _window_ring(geometry, where), index
        elif kind == "LineString":
            polylines.append(_trace_line(geometry.get("coordinates"), where, "coordinates"))
            records.append(props)
        elif kind == "MultiLineString":
            parts = _multi_parts(geometry.get("coordinates"), where)
            split_any |= _add_multi_line(parts, props, polylines, records, where)
        else:
            raise ValueError(
                f"{where}: geometry type {kind!r} is not a trace; expected LineString or MultiLineString "
                "(or a Polygon for the sampling window)"
            )
    _number_parts(records, split_any)
    return _trace_map_of(polylines, records, window, crs, file_frame, frame, name,
                         rfc7946_default="crs" not in doc and file_frame is None)


def _trace_map_of(polylines, records, window, crs, file_frame, frame, name, **crs_rules) -> TraceMap:
    """The map of the traces and window a reader collected (GeoJSON here, GeoPackage and Shapefile
    in :mod:`~rockmass.dfn.gis_io`): the CRS checked against the coordinates
    (:func:`~rockmass.dfn.frames.check_crs`, ``crs_rules`` its keywords), rockmass's own local CRS
    of a face frame read back as no GIS CRS, the frame resolved; errors name the file."""
    every_xy = polylines + ([] if window is None else [window])
    check_crs(crs, np.concatenate(every_xy) if every_xy else np.zeros((0, 2)), name, **crs_rules)
    if is_rockmass_local_crs(crs):
        crs = None  # the face frame as rockmass writes it: no GIS CRS
    frame = _resolve_frame(file_frame, frame, name, default_frame(crs))
    try:
        return TraceMap.from_polylines(polylines, _columns(records), window=window, frame=frame, crs=crs)
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from exc


def _load_json(path: str | os.PathLike[str], name: str) -> Any:
    with open(path, encoding="utf-8-sig") as handle:
        try:
            return json.load(handle)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{name}: invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}") from exc
        except UnicodeDecodeError as exc:
            raise ValueError(f"{name}: not UTF-8 text ({exc.reason} at byte {exc.start})") from exc


def _feature_list(doc: Any, name: str) -> list[Any]:
    if not isinstance(doc, dict):
        raise ValueError(
            f"{name}: expected a GeoJSON object (FeatureCollection, Feature or geometry), "
            f"got a JSON {type(doc).__name__}"
        )
    kind = doc.get("type")
    if kind == "FeatureCollection":
        features = doc.get("features")
        if not isinstance(features, list):
            raise ValueError(f"{name}: features: expected a list of Feature objects, got {type(features).__name__}")
        return features
    if kind == "Feature":
        return [doc]
    if kind in _GEOMETRY_TYPES:
        return [{"type": "Feature", "geometry": doc, "properties": {}}]
    raise ValueError(f"{name}: type: expected 'FeatureCollection', 'Feature' or a geometry type, got {kind!r}")


def _read_crs(crs: Any, name: str) -> str | None:
    """The CRS name from a plain string or a legacy (GeoJSON 2008) crs object."""
    if crs is None or (isinstance(crs, str) and crs.strip()):
        return crs
    if isinstance(crs, dict) and isinstance(crs.get("properties"), dict):
        props = crs["properties"]
        if crs.get("type") == "name" and isinstance(props.get("name"), str) and props["name"].strip():
            return props["name"]
        if crs.get("type") == "EPSG" and isinstance(props.get("code"), int):
            return f"EPSG:{props['code']}"
    raise ValueError(
        f'{name}: crs: expected a string or {{"type": "name", "properties": {{"name": ...}}}}, '
        f"got {json.dumps(crs)[:80]}"
    )


def _read_frame(file_frame: Any, name: str) -> str | None:
    """The top-level ``frame`` member: absent (None) or a non-empty string."""
    if file_frame is not None and (not isinstance(file_frame, str) or not file_frame.strip()):
        raise ValueError(f"{name}: frame: expected a non-empty string naming the frame, got {file_frame!r}")
    return file_frame


def _where(name: str, index: int, feature: Any) -> str:
    """``"file: feature 12 (id=T13)"`` for messages."""
    fid = None
    if isinstance(feature, dict):
        props = feature.get("properties")
        if isinstance(props, dict) and props.get("id") is not None:
            fid = props["id"]
        elif feature.get("id") is not None:
            fid = feature["id"]
    return f"{name}: feature {index}" + ("" if fid is None else f" (id={fid})")


def _unpack_feature(feature: Any, where: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """(geometry, properties) of a Feature; the feature's own ``id`` fills a missing ``properties.id``."""
    if not isinstance(feature, dict) or feature.get("type") != "Feature":
        raise ValueError(f"{where}: expected a GeoJSON Feature object, got {json.dumps(feature)[:80]}")
    geometry = feature.get("geometry")
    if geometry is None:
        raise ValueError(f"{where}: geometry is null; every feature needs a LineString trace (or the window Polygon)")
    if not isinstance(geometry, dict) or geometry.get("type") not in _GEOMETRY_TYPES:
        raise ValueError(f"{where}: geometry: expected a GeoJSON geometry object, got {json.dumps(geometry)[:80]}")
    props = feature.get("properties")
    if props is None:
        props = {}
    if not isinstance(props, dict):
        raise ValueError(f"{where}: properties: expected an object or null, got {type(props).__name__}")
    props = dict(props)
    if props.get("id") is None and feature.get("id") is not None:
        props["id"] = feature["id"]
    return geometry, props


def _positions(coords: Any, where: str, field: str) -> np.ndarray:
    """(k, 2) float64 x, y from a list of GeoJSON positions; z/m values are dropped."""
    if not isinstance(coords, list):
        raise ValueError(f"{where}: {field}: expected a list of [x, y] positions, got {json.dumps(coords)[:60]}")
    if not coords:
        return np.zeros((0, 2))
    try:
        array = np.array(coords)
    except (ValueError, TypeError):  # ragged: mixed 2D / 3D positions, or a malformed one
        array = None
    if (array is not None and array.ndim == 2 and array.shape[1] >= 2 and array.dtype.kind in "iuf"
            and not any(type(c) is bool for position in coords for c in position)):  # numpy: True -> 1
        xy = array[:, :2].astype(np.float64)
    else:
        for k, position in enumerate(coords):
            if not (
                isinstance(position, list)
                and len(position) >= 2
                and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in position[:2])
            ):
                raise ValueError(
                    f"{where}: {field}[{k}]: expected a position [x, y] or [x, y, z] of numbers, "
                    f"got {json.dumps(position)[:60]}"
                )
        xy = np.array([[_as_float(c) for c in position[:2]] for position in coords], dtype=np.float64)
    bad = np.flatnonzero(~np.isfinite(xy).all(axis=1))
    if bad.size:
        raise ValueError(f"{where}: {field} contain NaN/Infinity at positions {bad[:_MAX_LISTED].tolist()}")
    far = np.flatnonzero(_beyond_range(xy))
    if far.size:
        raise ValueError(f"{where}: {field} beyond ±{MAX_COORDINATE_M:.0e} m at positions "
                         f"{far[:_MAX_LISTED].tolist()}; coordinates are metres in the face or map frame")
    return xy


def _as_float(number: int | float) -> float:
    """A JSON number as a float; an integer too large for one (JSON has no limit) as the largest
    float of its sign, which the range check then reports."""
    try:
        return float(number)
    except OverflowError:
        return float(np.finfo(np.float64).max) * (1 if number > 0 else -1)


def _trace_line(coords: Any, where: str, field: str) -> np.ndarray:
    xy = _positions(coords, where, field)
    if xy.shape[0] < 2:
        raise ValueError(f"{where}: {field} has {xy.shape[0]} position(s); a trace needs at least 2")
    return xy


def _multi_parts(coords: Any, where: str) -> list[np.ndarray]:
    if not isinstance(coords, list) or not coords:
        raise ValueError(f"{where}: coordinates: a MultiLineString needs a non-empty list of parts")
    return [_trace_line(part, where, f"coordinates[{k}]") for k, part in enumerate(coords)]


def _add_multi_line(
    parts: list[np.ndarray], props: dict[str, Any], polylines: list[np.ndarray], records: list[dict[str, Any]],
    where: str,
) -> bool:
    """Append a MultiLineString's trace(s) by the rule of the module docstring; True if it was split.

    Its parts become one trace when :func:`shapely.line_merge` joins them into one line, else one
    trace each, numbered by a ``part`` property (GeoPackage and Shapefile features follow the same
    rule, :mod:`rockmass.dfn.gis_io`).
    """
    merged = shapely.line_merge(shapely.MultiLineString(parts))
    if merged.geom_type == "LineString":
        polylines.append(shapely.get_coordinates(merged))
        records.append(props)
        return False
    if "part" in props:
        raise ValueError(
            f"{where}: properties already have a 'part' field, which the reader needs to number "
            "the parts of a MultiLineString whose parts do not join; rename that property"
        )
    polylines.extend(parts)
    records.extend({**props, "part": k} for k in range(len(parts)))
    return True


def _number_parts(records: list[dict[str, Any]], split_any: bool) -> None:
    """When any feature was split, traces that came whole get ``part = -1``."""
    if split_any:
        for record in records:
            record.setdefault("part", -1)


def _window_ring(geometry: dict[str, Any], where: str) -> np.ndarray:
    """Exterior ring of the window from a Polygon (no holes) or a closed LineString."""
    kind, coords = geometry["type"], geometry.get("coordinates")
    if kind == "Polygon":
        if not isinstance(coords, list) or not coords:
            raise ValueError(f"{where}: coordinates: a window Polygon needs an exterior ring")
        if len(coords) > 1:
            raise ValueError(f"{where}: the window polygon has {len(coords) - 1} hole(s); holes are not supported")
        ring = _positions(coords[0], where, "coordinates[0]")
    elif kind == "LineString":
        ring = _positions(coords, where, "coordinates")
        if ring.shape[0] < 4 or not np.array_equal(ring[0], ring[-1]):
            raise ValueError(f"{where}: role 'window' needs a closed ring, but this LineString is not closed")
    else:
        raise ValueError(f"{where}: role 'window' needs a Polygon (or a closed LineString), got {kind!r}")
    if ring.shape[0] < 4:
        raise ValueError(f"{where}: the window ring has {ring.shape[0]} positions; a closed ring needs at least 4")
    try:
        return _as_window(ring)
    except ValueError as exc:  # e.g. zero area
        raise ValueError(f"{where}: {exc}") from exc


def _json_kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int" if _INT64.min <= value <= _INT64.max else "float"
    if isinstance(value, float):
        return "float"
    return "str" if isinstance(value, str) else "other"


def _as_text(value: Any) -> str:
    if value is _MISSING:
        return ""
    return value if isinstance(value, str) else json.dumps(value, ensure_ascii=False)


def _column(values: list[Any]) -> np.ndarray:
    """One attribute column from JSON values (None = missing), by the rules in the module docstring."""
    present = [v for v in values if v is not _MISSING]
    kinds = {_json_kind(v) for v in present}
    complete = len(present) == len(values)
    if (kinds == {"bool"} or kinds == {"int"}) and complete:
        return np.array(values, dtype=bool if kinds == {"bool"} else np.int64)
    if kinds <= {"int", "float"} or kinds == {"bool"}:  # numbers with gaps (or no value at all)
        return np.array([np.nan if v is _MISSING else float(v) for v in values], dtype=np.float64)
    return np.array([_as_text(v) for v in values], dtype=str)


def _id_column(values: list[Any]) -> np.ndarray | None:
    """The id column: int64 when every id is integer-valued (missing: -1), else str (missing: '')."""
    present = [v for v in values if v is not _MISSING]
    if not present:
        return None
    if all(
        _json_kind(v) == "int" or (_json_kind(v) == "float" and float(v).is_integer() and abs(v) < 2.0**63)
        for v in present
    ):
        return np.array([-1 if v is _MISSING else int(v) for v in values], dtype=np.int64)
    return np.array([_as_text(v) for v in values], dtype=str)


def _columns(records: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    names = list(dict.fromkeys(key for record in records for key in record))
    columns = {}
    for key in names:
        values = [record.get(key) for record in records]
        column = _id_column(values) if key == "id" else _column(values)
        if column is not None:
            columns[key] = column
    return columns


# -- writing -------------------------------------------------------------------------------------


def write_geojson(trace_map: TraceMap, path: str | os.PathLike[str]) -> None:
    """Write a trace map as a GeoJSON FeatureCollection, atomically.

    Parameters
    ----------
    trace_map : TraceMap
        The map to write; it is not modified.
    path : str or path-like
        Destination; replaced only once the whole file is written.

    Raises
    ------
    ValueError
        If a float attribute holds ±Infinity (JSON cannot store it), or a trace's ``role`` attribute
        is ``"window"`` (it would be read back as the window).
    OSError
        If the file cannot be written.

    Notes
    -----
    NaN attribute values are written as null and read back as NaN. The window, when present, is
    the last feature. See the module docstring of :mod:`rockmass.dfn.geojson_io` for the layout.
    """
    _require_trace_map(trace_map)
    name = os.fspath(path)
    ids = trace_map.attributes["id"]
    properties = {}
    for key, column in trace_map.attributes.items():
        values = column.tolist()
        if column.dtype.kind == "f":
            infinite = np.flatnonzero(np.isinf(column))
            if infinite.size:
                raise ValueError(
                    f"{name}: attribute {key!r} is infinite for traces {_describe_traces(infinite, ids)}; "
                    "JSON cannot store Infinity"
                )
            for i in np.flatnonzero(np.isnan(column)):
                values[i] = None
        properties[key] = values
    if "role" in properties:
        clash = np.flatnonzero(trace_map.attributes["role"] == "window")
        if clash.size:
            raise ValueError(
                f"{name}: attribute 'role' is 'window' for traces {_describe_traces(clash, ids)}; "
                "they would be read back as the sampling window"
            )
    head: dict[str, Any] = {"type": "FeatureCollection", "frame": trace_map.frame,
                            "angle_convention": angle_convention(trace_map.frame)}
    # a map without a GIS CRS (a face frame) names a local engineering CRS, so that a GIS does not
    # take it for WGS 84 longitude / latitude (RFC 7946's default)
    crs = trace_map.crs if trace_map.crs is not None else local_crs_wkt(trace_map.frame)
    head["crs"] = {"type": "name", "properties": {"name": crs}}
    xy, offsets = trace_map.xy_m, trace_map.offsets
    with atomic_open(path) as handle:
        handle.write(json.dumps(head, ensure_ascii=False)[:-1] + ', "features": [')
        separator = "\n"
        for i in range(trace_map.n_traces):
            feature = {
                "type": "Feature",
                "properties": {key: values[i] for key, values in properties.items()},
                "geometry": {"type": "LineString", "coordinates": xy[offsets[i] : offsets[i + 1]].tolist()},
            }
            handle.write(separator + _dump(feature))
            separator = ",\n"
        if trace_map.window_xy_m is not None:
            ring = trace_map.window_xy_m.tolist()
            feature = {
                "type": "Feature",
                "properties": {"role": "window"},
                "geometry": {"type": "Polygon", "coordinates": [ring + ring[:1]]},
            }
            handle.write(separator + _dump(feature))
        handle.write("\n]}\n")


def _dump(feature: dict[str, Any]) -> str:
    return json.dumps(feature, ensure_ascii=False, allow_nan=False)
