"""The pixel size and map position of a GeoTIFF photograph (a drone orthophoto or a tile of one),
from its GeoTIFF tags (OGC GeoTIFF Standard 1.1, 2019; docs/imaging.md §1.1).

A GeoTIFF ties its raster to a map by tags: ``ModelPixelScaleTag`` (33550) holds the pixel size
(S_x, S_y, S_z) in the model's units, ``ModelTiepointTag`` (33922) a raster point (i, j, k) and the
map point (X, Y, Z) it lies on, and ``GeoKeyDirectoryTag`` (34735) the keys that name the model:
``GTModelTypeGeoKey`` (1024; 1 projected, 2 geographic), ``GTRasterTypeGeoKey`` (1025; 1 a pixel
is an area, 2 a point), ``ProjectedCSTypeGeoKey`` (3072; the EPSG code) and
``ProjLinearUnitsGeoKey`` (3076; 9001 metre). For a north-up grid the map position of the raster
position (row r, column c) is

    X = X₀ + (c − i) S_x,   Y = Y₀ − (r − j) S_y                                        (1.3)

with raster positions counted from the grid's corner in a pixel-is-area grid and from the first
pixel's centre in a pixel-is-point grid. A grid is read only when it is north up (no ``ModelTransformationTag``, 34264, with
rotation), projected, in metres, and its pixels are square within 1 %: then its pixel size is a
scale ``rockmass extract`` can use. The tags are read with Pillow (a matplotlib dependency); no
GDAL is needed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

__all__ = ["GeoReference", "read_georeference", "to_map"]

_PIXEL_SCALE, _TIEPOINT, _TRANSFORMATION, _GEOKEYS = 33550, 33922, 34264, 34735
_MODEL_TYPE, _RASTER_TYPE, _PROJECTED_CRS, _LINEAR_UNITS = 1024, 1025, 3072, 3076
_PROJECTED, _PIXEL_IS_POINT, _METRE, _USER_DEFINED = 1, 2, 9001, 32767
#: Largest relative difference of S_x and S_y for the pixels to count as square.
SQUARE_TOLERANCE = 0.01


@dataclass(frozen=True)
class GeoReference:
    """Where a north-up GeoTIFF lies on its map.

    Attributes
    ----------
    pixel_size_m : (float, float)
        (S_x, S_y), metres.
    corner_xy_m : (float, float)
        Map coordinates of the top-left corner of the top-left pixel, metres.
    crs : str
        ``"EPSG:<code>"`` of the projected coordinate reference system.
    """

    pixel_size_m: tuple[float, float]
    corner_xy_m: tuple[float, float]
    crs: str

    @property
    def m_per_px(self) -> float:
        """The scale: the geometric mean of S_x and S_y."""
        return float((self.pixel_size_m[0] * self.pixel_size_m[1]) ** 0.5)

    def to_dict(self) -> dict:
        return {"crs": self.crs, "pixel_size_m": list(self.pixel_size_m),
                "corner_xy_m": list(self.corner_xy_m), "m_per_px": self.m_per_px}

    @classmethod
    def from_dict(cls, record) -> GeoReference:
        """The inverse of :meth:`to_dict` (``m_per_px`` follows from the pixel size)."""
        return cls(pixel_size_m=tuple(map(float, record["pixel_size_m"])),
                   corner_xy_m=tuple(map(float, record["corner_xy_m"])), crs=str(record["crs"]))


def _geokeys(directory) -> dict[int, int]:
    """Key id -> value of the keys stored in the directory itself (TIFFTagLocation 0)."""
    values = [int(v) for v in directory]
    keys = {}
    for k in range(4, 4 + 4 * values[3], 4):
        key, location, count, value = values[k:k + 4]
        if location == 0 and count == 1:
            keys[key] = value
    return keys


def read_georeference(path, max_pixels: int | None = None) -> GeoReference | None:
    """The :class:`GeoReference` of a GeoTIFF, or None for a file that is not one or whose grid is
    not a north-up, projected, metre grid of square pixels (see the module notes).

    Only the header is read. ``max_pixels`` raises Pillow's decompression-bomb guard for it as
    :func:`rockmass.imaging.enhance.read_photo` does, so that a large orthophoto the photo reader
    accepts keeps its georeference.

    Examples
    --------
    >>> read_georeference("photo.jpg") is None  # not a TIFF: not even opened
    True
    """
    if Path(path).suffix.lower() not in (".tif", ".tiff"):
        return None
    from PIL import Image

    from .enhance import _pillow_pixel_limit

    try:
        with _pillow_pixel_limit(Image, max_pixels), Image.open(path) as image:
            tags = dict(getattr(image, "tag_v2", {}))
    except OSError:
        return None  # the photo reader says what is wrong with the file
    try:
        return _from_tags(tags)
    except (IndexError, TypeError, ValueError):  # malformed tags: not a usable georeference
        return None


def _from_tags(tags) -> GeoReference | None:
    """:func:`read_georeference` of the tags of an opened TIFF (tag number -> value)."""
    scale, tiepoint, directory = tags.get(_PIXEL_SCALE), tags.get(_TIEPOINT), tags.get(_GEOKEYS)
    if scale is None or tiepoint is None or directory is None or len(tiepoint) < 6:
        return None
    transformation = tags.get(_TRANSFORMATION)
    if transformation is not None and any(abs(float(transformation[k])) > 0 for k in (1, 4)):
        return None  # rotated or sheared
    keys = _geokeys(directory)
    if keys.get(_MODEL_TYPE) != _PROJECTED or keys.get(_LINEAR_UNITS) != _METRE:
        return None
    code = keys.get(_PROJECTED_CRS)
    if code is None or code == _USER_DEFINED:
        return None
    s_x, s_y = float(scale[0]), float(scale[1])
    if not (s_x > 0 and s_y > 0) or abs(s_x - s_y) > SQUARE_TOLERANCE * 0.5 * (s_x + s_y):
        return None
    i, j, x0, y0 = (float(tiepoint[k]) for k in (0, 1, 3, 4))
    if keys.get(_RASTER_TYPE) == _PIXEL_IS_POINT:  # raster points at pixel centres
        i, j = i + 0.5, j + 0.5
    return GeoReference(pixel_size_m=(s_x, s_y), corner_xy_m=(x0 - i * s_x, y0 + j * s_y),
                        crs=f"EPSG:{code}")


def to_map(trace_map, reference: GeoReference, height_px: int):
    """The traces of a photo ``height_px`` rows high, extracted at the scale s =
    ``reference.m_per_px``, in the map coordinates of its georeference.

    A face-frame point (u, v) (docs/imaging.md eq. (1.1)) is at column c = u/s − ½ and row
    r = H − v/s − ½ of the photo, the centre of pixel (r, c) at raster position (r + ½, c + ½),
    which eq. (1.3) puts at

        X = X_c + u · S_x / s,     Y = Y_c − H · S_y + v · S_y / s

    with (X_c, Y_c) the photo's top-left corner on the map (``corner_xy_m``). The result is in
    frame "map" with the reference's CRS; its ``angle_deg`` attribute is the azimuth of each trace
    (clockwise from North, 0–180°, of the map geometry) and ``length_m`` its map length, so that
    the file reads as a map's traces do (docs/fractures.md, frames). The sampling window moves
    with the traces.
    """
    from ..dfn.frames import MAP_FRAME, to_convention
    from .vectorize import axial_angle_deg

    s = reference.m_per_px
    stretch = np.array(reference.pixel_size_m) / s
    shift = np.array([reference.corner_xy_m[0],
                      reference.corner_xy_m[1] - height_px * reference.pixel_size_m[1]])
    window = trace_map.window_xy_m
    mapped = replace(trace_map, xy_m=trace_map.xy_m * stretch + shift, frame=MAP_FRAME,
                     crs=reference.crs, window_xy_m=None if window is None else window * stretch + shift)
    attributes = dict(mapped.attributes)
    if "angle_deg" in attributes:
        attributes["angle_deg"] = to_convention(axial_angle_deg(mapped), "azimuth")
    if "length_m" in attributes:
        attributes["length_m"] = mapped.lengths_m()
    return replace(mapped, attributes=attributes)
