"""GeoTIFF georeference: the pixel size becomes the scale of a drone tile (docs/imaging.md §1.1).

The files are written here with Pillow's TIFF tags, as GDAL writes a north-up UTM tile; the
expected values follow from the tags by eq. (1.3) of docs/imaging.md §1.1."""

import json

import numpy as np
import pytest
from PIL import Image, TiffImagePlugin

from rockmass.cli import main
from rockmass.dfn import read_traces
from rockmass.imaging.georef import read_georeference

DOUBLE, SHORT = 12, 3


def _keys(*entries):
    """A GeoKeyDirectory: header (1, 1, 0, n) and (key, 0, 1, value) per entry."""
    out = [1, 1, 0, len(entries)]
    for key, value in entries:
        out += [key, 0, 1, value]
    return tuple(out)


def _geotiff(path, *, scale=(0.05, 0.05, 0.0), tiepoint=(0.0, 0.0, 0.0, 648185.0, 9385159.0, 0.0),
             keys=((1024, 1), (1025, 1), (3072, 31984), (3076, 9001)), image=None,
             transformation=None):
    info = TiffImagePlugin.ImageFileDirectory_v2()
    for tag, value, kind in ((33550, scale, DOUBLE), (33922, tiepoint, DOUBLE),
                             (34735, _keys(*keys), SHORT), (34264, transformation, DOUBLE)):
        if value is not None:
            info[tag] = value
            info.tagtype[tag] = kind
    pixels = image if image is not None else np.full((40, 60, 3), 128, np.uint8)
    Image.fromarray(pixels).save(path, tiffinfo=info)
    return path


def test_a_north_up_utm_tile_gives_its_pixel_size_crs_and_corner(tmp_path):
    ref = read_georeference(_geotiff(tmp_path / "tile.tif"))
    assert ref.crs == "EPSG:31984"
    assert ref.m_per_px == pytest.approx(0.05, rel=1e-12)
    assert ref.corner_xy_m == pytest.approx((648185.0, 9385159.0))


def test_the_tiepoint_and_pixel_is_point_move_the_corner_by_eq_1_3(tmp_path):
    """Tie raster (10, 20) to (1000, 2000) with 0.5 m pixels: the corner of pixel (0, 0) is at
    X = 1000 − 10·0.5, Y = 2000 + 20·0.5 (pixel is area), half a pixel further with pixel is point."""
    tie = (10.0, 20.0, 0.0, 1000.0, 2000.0, 0.0)
    area = read_georeference(_geotiff(tmp_path / "a.tif", scale=(0.5, 0.5, 0.0), tiepoint=tie))
    point = read_georeference(_geotiff(tmp_path / "p.tif", scale=(0.5, 0.5, 0.0), tiepoint=tie,
                                       keys=((1024, 1), (1025, 2), (3072, 32633), (3076, 9001))))
    assert area.corner_xy_m == pytest.approx((995.0, 2010.0))
    assert point.corner_xy_m == pytest.approx((994.75, 2010.25))


@pytest.mark.parametrize("change", [
    dict(keys=((1024, 2), (1025, 1), (2048, 4326))),                   # geographic: degrees
    dict(keys=((1024, 1), (1025, 1), (3072, 2263), (3076, 9002))),     # projected, in feet
    dict(keys=((1024, 1), (1025, 1), (3072, 31984))),                  # units not stated
    dict(scale=(0.05, 0.06, 0.0)),                                     # pixels not square
    dict(scale=None),                                                  # no pixel size
    dict(transformation=(0.0433, 0.025, 0, 648185.0, 0.025, -0.0433, 0, 9385159.0,
                         0, 0, 0, 0, 0, 0, 0, 1)),                     # rotated by 30°
])
def test_grids_that_are_not_north_up_metres_are_not_read(tmp_path, change):
    assert read_georeference(_geotiff(tmp_path / "tile.tif", **change)) is None


def test_malformed_tags_are_no_georeference_not_a_crash(tmp_path):
    """A key directory that claims more keys than it holds, and a tiepoint too short."""
    info = TiffImagePlugin.ImageFileDirectory_v2()
    info[33550], info.tagtype[33550] = (0.05, 0.05, 0.0), DOUBLE
    info[33922], info.tagtype[33922] = (0.0, 0.0, 0.0, 1.0, 2.0, 0.0), DOUBLE
    info[34735], info.tagtype[34735] = (1, 1, 0, 9, 1024, 0, 1, 1), SHORT
    path = tmp_path / "bad.tif"
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(path, tiffinfo=info)
    assert read_georeference(path) is None
    assert read_georeference(_geotiff(tmp_path / "short.tif", tiepoint=(0.0, 0.0, 0.0))) is None


def test_an_orthophoto_beyond_pillows_guard_keeps_its_georeference(tmp_path, monkeypatch):
    """Pillow refuses to open an image of more than twice ``Image.MAX_IMAGE_PIXELS``; a photo the
    reader accepts (``max_pixels``, as ``rockmass extract --max-pixels`` passes it) must keep its
    scale. The guard is lowered here so that a 40 x 60 tile lies beyond it."""
    photo = _geotiff(tmp_path / "big.tif")
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 500)
    with pytest.raises(Image.DecompressionBombError):
        read_georeference(photo)  # Pillow's own guard, when no limit is passed
    assert read_georeference(photo, max_pixels=10_000).m_per_px == pytest.approx(0.05)


def test_a_plain_tiff_and_other_photos_have_no_georeference(tmp_path):
    plain = tmp_path / "plain.tif"
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(plain)
    assert read_georeference(plain) is None
    assert read_georeference(tmp_path / "missing.jpg") is None


def test_extract_takes_the_scale_from_a_geotiff_and_records_it(tmp_path, capsys):
    from rockmass.imaging import synthetic_face

    face = synthetic_face("easy", seed=3, shape_px=(240, 360), m_per_px=0.02)
    rgb = np.repeat(face.image[..., None], 3, axis=2)
    photo = _geotiff(tmp_path / "tile.tif", scale=(0.02, 0.02, 0.0), image=rgb)
    assert main(["extract", str(photo), "--out", str(tmp_path / "out"), "--detector", "ridge"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["extraction"]["scale"]["m_per_px"] == pytest.approx(0.02)
    assert summary["extraction"]["scale"]["units"] == "m"
    assert summary["input"]["georeference"]["crs"] == "EPSG:31984"
    assert "from the GeoTIFF tags (EPSG:31984" in capsys.readouterr().out
    # the same traces on the map: eq. (1.3) through the corner, azimuths, the CRS
    face_traces = read_traces(tmp_path / "out" / "traces.geojson")
    map_traces = read_traces(tmp_path / "out" / "traces_map.geojson")
    assert map_traces.crs == "EPSG:31984" and map_traces.frame == "map"
    assert face_traces.n_traces == map_traces.n_traces >= 3
    corner = np.array([648185.0, 9385159.0 - 240 * 0.02])
    assert np.allclose(map_traces.xy_m, face_traces.xy_m + corner, atol=1e-6)
    assert np.allclose(map_traces.attributes["angle_deg"],
                       np.mod(90.0 - face_traces.attributes["angle_deg"], 180.0), atol=1e-6)
    assert np.allclose(map_traces.lengths_m(), face_traces.lengths_m())
    # a scale given by the user wins over the tags, and the map file of the last run goes
    assert main(["extract", str(photo), "--out", str(tmp_path / "out"), "--detector", "ridge",
                 "--m-per-px", "0.03"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["extraction"]["scale"]["m_per_px"] == pytest.approx(0.03)
    assert "georeference" not in summary["input"]
    assert not (tmp_path / "out" / "traces_map.geojson").exists()


def test_a_face_frame_point_lies_on_the_map_where_the_docs_say(tmp_path):
    """docs/imaging.md §1.1: (u, v) of the face frame lies at (X_c + u, Y_c − H·s + v); checked at
    pixel centres against eq. (1.3) applied to the tags (raster point of a pixel-is-area grid at
    the centre of pixel (row, col): (col + ½, row + ½))."""
    from rockmass.imaging.frame import rc_to_uv

    tie, s, height = (10.0, 20.0, 0.0, 1000.0, 2000.0, 0.0), 0.5, 40
    ref = read_georeference(_geotiff(tmp_path / "a.tif", scale=(s, s, 0.0), tiepoint=tie))
    rc = np.array([[0, 0], [39, 59], [17, 23]])
    uv = rc_to_uv(rc, height_px=height, m_per_px=ref.m_per_px)
    mapped = np.column_stack([ref.corner_xy_m[0] + uv[:, 0],
                              ref.corner_xy_m[1] - height * s + uv[:, 1]])
    eq_1_3 = np.column_stack([tie[3] + (rc[:, 1] + 0.5 - tie[0]) * s,
                              tie[4] - (rc[:, 0] + 0.5 - tie[1]) * s])
    assert np.allclose(mapped, eq_1_3)
