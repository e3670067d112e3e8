"""GeoPackage and Shapefile trace files, read and written through pyogrio (GDAL), an optional extra.

QGIS and fractopo users keep traces and their target area as layers of a GeoPackage, or as one
Shapefile each. pyogrio (with the GDAL it bundles) is imported only when such a file is read or
written; without it the error says to ``pip install 'rockmass[gis]'``.

Reading (:func:`read_gis`)
--------------------------
- **Which layer holds the traces.** ``layer=`` names it. Otherwise the file's line layers
  (LineString / MultiLineString, with or without z) are the candidates: the only one, else the one
  named ``traces`` (the name :func:`write_gis` uses); several without a ``traces`` layer is an error
  that names the file and lists its layers with their geometry types. A file without a line layer
  holds no traces (an area file), unless it has no polygon layer either (an error).
- **Features.** The same rules as GeoJSON (:mod:`rockmass.dfn.geojson_io`): a LineString is a trace,
  a MultiLineString is merged into one trace when its parts join, else split (numbered by ``part``);
  z values are dropped. A null geometry, a point or a polygon in the traces layer is an error naming
  the file, the layer and the feature (0-based index in the layer, with its fid). Fields become
  attribute columns by the GeoJSON typing rules (a null number is NaN, a null string ``''``).
- **The area (sampling window).** The polygon layer: the only one, else the one named ``area``;
  several without an ``area`` layer is an error listing them. It must hold one polygon (or a
  MultiPolygon of one part) without holes; fractopo's several target areas per file are an error,
  as a trace map has one window.
- **CRS.** The layers' CRS (the same in both, else an error) is checked by
  :func:`rockmass.dfn.frames.check_crs`: a geographic CRS is refused with how to reproject. The
  local CRS that :func:`write_gis` names a face frame with gives the map no CRS again. The frame is
  the ``frame`` item of the layer's metadata (written to GeoPackages), else ``"map"`` with a CRS,
  ``"face"`` without.

Writing (:func:`write_gis`)
---------------------------
A GeoPackage gets the layers ``traces`` (LineString), ``area`` (Polygon, when the map has a window)
and, given a :class:`~rockmass.dfn.branches.BranchesAndNodes`, ``nodes`` (Point) and ``branches``
(LineString). A Shapefile path ``DIR/NAME.shp`` is the traces layer; the others are written beside
it as ``NAME_area.shp``, ``NAME_nodes.shp``, ``NAME_branches.shp`` (each with its ``.shx``,
``.dbf``, ``.prj`` and ``.cpg``). Field names are fractopo's where fractopo has one
(:data:`CLASS_FIELD`, :data:`CONNECTION_FIELD`, :data:`VALIDATION_FIELD`); Shapefile names are cut
to 10 characters as the dBase format requires (``VALIDATION_ERRORS`` becomes ``VALIDATION``, as in
fractopo), and two fields that would get the same name are an error. Every layer carries the map's
CRS, or the WKT ``LOCAL_CS`` of its frame (:func:`rockmass.dfn.frames.local_crs_wkt`) when it has
none, so a GIS never takes a face map for WGS 84.

A GeoPackage is written under a temporary name in the destination's folder and renamed into
place (:mod:`rockmass.dfn.atomic`): a failed write leaves the previous file as it was. Shapefile
layers are all written to a temporary folder first, then renamed file by file, each ``.shp``
last (a failure while writing leaves the previous files; the renames are not one step).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from .atomic import atomic_path
from .frames import angle_convention, local_crs_wkt
from .geojson_io import _add_multi_line, _number_parts, _trace_line, _trace_map_of
from .tracemap import TraceMap, _as_window, _require_trace_map

__all__ = ["read_gis", "write_gis"]  # constants: import them by module

#: Suffix -> GDAL driver of the formats this module reads and writes.
GIS_SUFFIXES = {".gpkg": "GPKG", ".shp": "ESRI Shapefile"}
#: Layer names :func:`write_gis` writes (and :func:`read_gis` prefers when a file has several).
TRACES_LAYER, AREA_LAYER, NODES_LAYER, BRANCHES_LAYER = "traces", "area", "nodes", "branches"
#: fractopo's field names (``fractopo.general``: ``CLASS_COLUMN``, ``CONNECTION_COLUMN``,
#: ``Validation.ERROR_COLUMN``).
CLASS_FIELD, CONNECTION_FIELD, VALIDATION_FIELD = "Class", "Connection", "VALIDATION_ERRORS"
#: What to install for this module.
PIP_HINT = "pip install 'rockmass[gis]'"

_LINE_TYPES = frozenset({"LineString", "MultiLineString"})
_POLYGON_TYPES = frozenset({"Polygon", "MultiPolygon"})
_SHAPEFILE_FIELD_CHARS = 10  # dBase field names


def require_pyogrio() -> Any:
    """The pyogrio module; ImportError saying how to install it when it is missing."""
    try:
        import pyogrio
    except ImportError as exc:
        raise ImportError(
            f"GeoPackage and Shapefile files need the optional package pyogrio: {PIP_HINT} "
            "(or pip install pyogrio); GeoJSON and CSV work without it") from exc
    return pyogrio


def _base_type(geometry_type: Any) -> str:
    """``"LineString Z"`` / ``"3D LineString"`` / ``"LineString M"`` -> ``"LineString"``."""
    text = str(geometry_type).replace("3D ", "")
    return text.split(" ")[0]


# -- reading -------------------------------------------------------------------------------------


def read_gis(path: str | os.PathLike[str], *, frame: str | None = None, layer: str | None = None) -> TraceMap:
    """Read traces (and the area polygon) from a GeoPackage or Shapefile.

    Parameters
    ----------
    path : str or path-like
        A ``.gpkg`` or ``.shp`` file.
    frame : str, optional
        Frame for a file that names none; a file naming another frame is an error. Default None.
    layer : str, optional
        The layer holding the traces. Default None: the only line layer, else the one named
        ``traces``.

    Returns
    -------
    TraceMap
        With the area polygon as its window when the file has one.

    Raises
    ------
    ImportError
        pyogrio is not installed (the message says ``pip install 'rockmass[gis]'``).
    ValueError
        Ambiguous or missing layers (the message lists them), a feature that is not a trace (naming
        file, layer and feature), several area polygons, differing or geographic CRSs.
    OSError
        The file cannot be read.

    Notes
    -----
    The layer, feature, area and CRS rules are in the module docstring of
    :mod:`rockmass.dfn.gis_io`.
    """
    pyogrio = require_pyogrio()
    name = os.fspath(path)
    if not os.path.exists(name):
        raise FileNotFoundError(2, "No such file or directory", name)
    try:
        listed = pyogrio.list_layers(name)
    except pyogrio.errors.DataSourceError as exc:
        gdal_says = str(exc).split(";")[0]  # GDAL's advice to name a driver does not apply here
        raise ValueError(f"{name}: not a readable GeoPackage or Shapefile ({gdal_says})") from exc
    layers = {str(n): _base_type(t) for n, t in listed}
    trace_layer = _pick_trace_layer(layers, layer, name)
    area_layer = _pick_layer(layers, _POLYGON_TYPES, AREA_LAYER, name, "area polygon",
                             exclude=trace_layer)
    if trace_layer is None and area_layer is None:
        raise ValueError(f"{name}: no line layer (traces) and no polygon layer (area); layers: "
                         f"{_describe_layers(layers)}")
    polylines: list[np.ndarray] = []
    records: list[dict[str, Any]] = []
    crs, file_frame = None, None
    gdal_errors = (pyogrio.errors.DataLayerError, pyogrio.errors.FeatureError,
                   pyogrio.errors.FieldError, pyogrio.errors.GeometryError, pyogrio.errors.CRSError)
    try:
        if trace_layer is not None:
            crs, file_frame = _read_trace_layer(pyogrio, name, trace_layer, polylines, records)
        window = None
        if area_layer is not None:
            window, area_crs = _read_area_layer(pyogrio, name, area_layer)
    except gdal_errors as exc:  # a damaged layer is bad input (exit 2), named with its file
        raise ValueError(f"{name}: a layer GDAL cannot read ({exc})") from exc
    if area_layer is not None:
        if trace_layer is not None and area_crs != crs:
            raise ValueError(f"{name}: layer {area_layer!r} is in crs {area_crs!r} but layer {trace_layer!r} is "
                             f"in {crs!r}; give both in one CRS")
        crs = area_crs if trace_layer is None else crs
    return _trace_map_of(polylines, records, window, crs, file_frame, frame, name)


def _describe_layers(layers: dict[str, str]) -> str:
    return ", ".join(f"{n!r} ({t})" for n, t in layers.items()) or "none"


def _pick_trace_layer(layers: dict[str, str], layer: str | None, name: str) -> str | None:
    if layer is None:
        return _pick_layer(layers, _LINE_TYPES, TRACES_LAYER, name, "traces")
    if layer not in layers:
        raise ValueError(f"{name}: layer {layer!r} is not in the file; its layers: {_describe_layers(layers)}")
    return layer


def _pick_layer(layers: dict[str, str], kinds: frozenset, preferred: str, name: str, what: str,
                exclude: str | None = None) -> str | None:
    """The only layer of a kind, else the one named ``preferred``; None if there is none."""
    candidates = [n for n, t in layers.items() if t in kinds and n != exclude]
    if len(candidates) <= 1:
        return candidates[0] if candidates else None
    if preferred in candidates:
        return preferred
    fix = ("name the layer with layer=NAME (--layer NAME on the command line), or call it 'traces'"
           if what == "traces" else f"call the area layer {preferred!r}, or keep one polygon layer")
    raise ValueError(f"{name}: {len(candidates)} layers could hold the {what}: {', '.join(map(repr, candidates))} "
                     f"(all layers: {_describe_layers(layers)}); {fix}")


def _fid_where(name: str, layer: str, index: int, fids: Any) -> str:
    fid = "" if fids is None else f" (fid {int(fids[index])})"
    return f"{name}: layer {layer!r}: feature {index}{fid}"


def _read_trace_layer(pyogrio: Any, name: str, layer: str, polylines: list, records: list) -> tuple:
    """Append the layer's traces and their fields; return (crs, frame from the layer's metadata)."""
    meta, fids, wkb, field_data = pyogrio.raw.read(name, layer=layer, return_fids=True)
    geometries = shapely.from_wkb(wkb) if wkb is not None else np.zeros(0, dtype=object)
    fields = [str(f) for f in meta["fields"]]
    columns = [_field_values(values) for values in field_data]
    split_any = False
    for index, geometry in enumerate(geometries):
        where = _fid_where(name, layer, index, fids)
        props = {field: column[index] for field, column in zip(fields, columns)}
        kind = None if geometry is None else geometry.geom_type
        if kind == "LineString":
            polylines.append(_trace_line(shapely.get_coordinates(geometry).tolist(), where, "geometry"))
            records.append(props)
        elif kind == "MultiLineString":
            parts = [_trace_line(shapely.get_coordinates(p).tolist(), where, f"geometry part {k}")
                     for k, p in enumerate(geometry.geoms)]
            if not parts:
                raise ValueError(f"{where}: the MultiLineString is empty; a trace needs at least 2 vertices")
            split_any |= _add_multi_line(parts, props, polylines, records, where)
        else:
            shown = "null (no geometry)" if kind is None else repr(kind)
            raise ValueError(f"{where}: geometry {shown} is not a trace; a traces layer holds LineString or "
                             "MultiLineString features (the area belongs in a polygon layer of its own)")
    _number_parts(records, split_any)
    metadata = pyogrio.read_info(name, layer=layer).get("layer_metadata") or {}
    return meta.get("crs"), metadata.get("frame")


def _field_values(values: np.ndarray) -> list[Any]:
    """A field's values as JSON-like Python values: NaN and null are None, dates are text."""
    out = []
    for value in values.tolist():
        if isinstance(value, float) and not np.isfinite(value):
            value = None if np.isnan(value) else value
        elif value is not None and not isinstance(value, (bool, int, float, str)):
            value = str(value)  # dates, times, binary blobs
        out.append(value)
    return out


def _read_area_layer(pyogrio: Any, name: str, layer: str) -> tuple[np.ndarray, str | None]:
    """The one polygon of the area layer as an open ring, and the layer's CRS."""
    meta, _, wkb, _ = pyogrio.raw.read(name, layer=layer, columns=[])
    geometries = list(shapely.from_wkb(wkb)) if wkb is not None else []
    polygons = [p for g in geometries if g is not None for p in shapely.get_parts(g)]
    if len(polygons) != 1:
        raise ValueError(
            f"{name}: layer {layer!r} holds {len(polygons)} polygons; a trace map has one sampling window "
            "(the mapped area): dissolve the area polygons into one, or analyse each area on its own")
    polygon = polygons[0]
    if polygon.geom_type != "Polygon":
        raise ValueError(f"{name}: layer {layer!r}: the area is a {polygon.geom_type}, not a Polygon")
    if len(polygon.interiors):
        raise ValueError(f"{name}: layer {layer!r}: the area polygon has {len(polygon.interiors)} hole(s); "
                         "holes are not supported")
    try:
        ring = _as_window(shapely.get_coordinates(polygon.exterior))
    except ValueError as exc:
        raise ValueError(f"{name}: layer {layer!r}: {exc}") from exc
    return ring, meta.get("crs")


# -- writing -------------------------------------------------------------------------------------


def write_gis(trace_map: TraceMap, path: str | os.PathLike[str], network: Any = None) -> list[Path]:
    """Write traces, area, nodes and branches as GeoPackage layers or Shapefiles, atomically.

    Parameters
    ----------
    trace_map : TraceMap
        The traces (their attributes become fields) and the window (the ``area`` layer); not modified.
    path : str or path-like
        ``NAME.gpkg`` (one file, one layer each) or ``NAME.shp`` (the traces; ``NAME_area.shp``,
        ``NAME_nodes.shp`` and ``NAME_branches.shp`` beside it).
    network : BranchesAndNodes, optional
        The nodes and branches of ``trace_map`` (:func:`rockmass.dfn.branches.branches_and_nodes`)
        for the ``nodes`` (field ``Class``) and ``branches`` (``Connection``, the ``trace_id`` of
        the trace it is a piece of, ``length``) layers. Default None: no topology layers.

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    ImportError
        pyogrio is not installed.
    ValueError
        An unknown suffix, or Shapefile field names that collide once cut to 10 characters.
    OSError
        A file cannot be written; previous files keep their content.
    """
    _require_trace_map(trace_map)
    target = Path(path)
    driver = GIS_SUFFIXES.get(target.suffix.lower())
    if driver is None:
        raise ValueError(f"{os.fspath(path)}: cannot write GIS layers to a {target.suffix!r} file; "
                         f"accepted suffixes: {', '.join(GIS_SUFFIXES)}")
    pyogrio = require_pyogrio()
    layers = _layers(trace_map, network)
    crs = trace_map.crs if trace_map.crs is not None else local_crs_wkt(trace_map.frame)
    metadata = {"frame": trace_map.frame, "angle_convention": angle_convention(trace_map.frame)}
    if driver == "GPKG":
        with atomic_path(target) as tmp:
            for layer, (geometries, geometry_type, fields) in layers.items():
                _write_layer(pyogrio, tmp, layer, geometries, geometry_type, fields, crs, driver, metadata)
        return [target]
    return _write_shapefiles(pyogrio, target, layers, crs)


def _layers(trace_map: TraceMap, network: Any) -> dict[str, tuple[np.ndarray, str, dict[str, np.ndarray]]]:
    """Each layer's (geometries, geometry type, fields) in writing order."""
    layers = {TRACES_LAYER: (trace_map.to_shapely(), "LineString", dict(trace_map.attributes))}
    if trace_map.window_xy_m is not None:
        layers[AREA_LAYER] = (np.array([trace_map.window_polygon()], dtype=object), "Polygon", {})
    if network is not None:
        layers[NODES_LAYER] = (shapely.points(network.nodes_xy_m).reshape(-1), "Point",
                               {CLASS_FIELD: network.node_class})
        layers[BRANCHES_LAYER] = (network.branch_lines(), "LineString",
                                  {CONNECTION_FIELD: network.connection,
                                   "trace_id": trace_map.attributes["id"][network.branch_trace],
                                   "length": network.branch_lengths_m()})
    return layers


def _ogr_column(values: np.ndarray) -> np.ndarray:
    """A column in the dtype pyogrio writes: text as object, anything else as is."""
    values = np.asarray(values)
    if values.dtype.kind == "U":
        return values.astype(object)
    return values


def _write_layer(pyogrio: Any, path: Path, layer: str, geometries: np.ndarray, geometry_type: str,
                 fields: dict[str, np.ndarray], crs: str, driver: str, metadata: dict | None) -> None:
    pyogrio.raw.write(
        os.fspath(path), shapely.to_wkb(geometries), [_ogr_column(v) for v in fields.values()],
        fields=list(fields), layer=layer, driver=driver, geometry_type=geometry_type, crs=crs,
        layer_metadata=metadata, promote_to_multi=False)


def _shapefile_fields(fields: dict[str, np.ndarray], shown: str) -> dict[str, np.ndarray]:
    """Fields renamed to dBase's 10 characters (``VALIDATION_ERRORS`` -> ``VALIDATION``, as fractopo
    does) and bool columns as 0 / 1 integers; names that collide once cut are an error."""
    out: dict[str, np.ndarray] = {}
    for field, values in fields.items():
        short = field[:_SHAPEFILE_FIELD_CHARS]
        if short.lower() in {k.lower() for k in out}:
            raise ValueError(f"{shown}: fields {field!r} and another both become {short!r} in a Shapefile (dBase "
                             "names have 10 characters); rename one, or write a GeoPackage")
        values = np.asarray(values)
        out[short] = values.astype(np.int64) if values.dtype.kind == "b" else values
    return out


#: The files of one Shapefile layer
_SHAPEFILE_PARTS = (".shp", ".shx", ".dbf", ".prj", ".cpg")


def _write_shapefiles(pyogrio: Any, target: Path, layers: dict, crs: str) -> list[Path]:
    """Every layer as a Shapefile (``NAME.shp`` the traces, ``NAME_<layer>.shp`` the others):
    all written into a temporary folder beside ``target`` first — a failure there leaves the
    previous files as they were — then renamed into place, each ``.shp`` last so that a reader
    never finds one before its ``.dbf``; layers an earlier write left and this one has not (an
    area, nodes, branches) are removed. GDAL cannot make the renames of several files one step:
    a GeoPackage (one file) is the all-or-nothing choice."""
    folder = Path(tempfile.mkdtemp(prefix=".tmp-", dir=target.parent))
    try:
        stems = []
        for layer, (geometries, geometry_type, fields) in layers.items():
            stem = target.stem if layer == TRACES_LAYER else f"{target.stem}_{layer}"
            _write_layer(pyogrio, folder / (stem + target.suffix), stem, geometries, geometry_type,
                         _shapefile_fields(fields, target.name), crs, "ESRI Shapefile", None)
            stems.append(stem)
        written = []
        for part in sorted(folder.iterdir(), key=lambda p: (p.suffix.lower() == ".shp", p.name)):
            destination = target.with_name(part.name)
            os.replace(part, destination)  # same folder: one atomic rename per file
            written.append(destination)
        for layer in (AREA_LAYER, NODES_LAYER, BRANCHES_LAYER):
            if f"{target.stem}_{layer}" not in stems:
                for suffix in _SHAPEFILE_PARTS:
                    target.with_name(f"{target.stem}_{layer}{suffix}").unlink(missing_ok=True)
        return written
    finally:
        with contextlib.suppress(OSError):
            shutil.rmtree(folder)
