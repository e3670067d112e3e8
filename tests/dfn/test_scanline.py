"""Scanline surveys: the CSV reader (header comments or TOML), strike/dip input, and bad files."""

import numpy as np
import pytest

from rockmass.dfn.orientation import pole_from_dip, vector_from_trend_plunge
from rockmass.dfn.scanline import Scanline, read_scanline

HEADER = "# trend: 90\n# plunge: 0\n# length: 10\n"
ROWS = "distance,dip,dip_direction,trace_length,termination\n1.0,30,120,2.5,1\n2.5,80,10,,0\n2.5,45,300,4,2\n"


def _write(folder, text, name="line.csv"):
    path = folder / name
    path.write_text(text)
    return path


def test_reader_returns_the_columns_and_the_line_geometry(tmp_path):
    scanline = read_scanline(_write(tmp_path, HEADER + ROWS))
    assert scanline.n_intersections == 3
    assert scanline.distance_m.tolist() == [1.0, 2.5, 2.5]
    assert scanline.dip_deg.tolist() == [30.0, 80.0, 45.0]
    assert scanline.dip_direction_deg.tolist() == [120.0, 10.0, 300.0]
    assert (scanline.trend_deg, scanline.plunge_deg, scanline.length_m) == (90.0, 0.0, 10.0)
    assert scanline.trace_length_m[0] == 2.5 and np.isnan(scanline.trace_length_m[1])  # blank: not measured
    assert scanline.termination == ("1", "0", "2")
    np.testing.assert_allclose(scanline.direction, [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(scanline.poles(), pole_from_dip([30, 80, 45], [120, 10, 300]))
    assert (scanline.poles()[:, 2] <= 0).all()
    assert scanline.spacings_m().tolist() == [1.5, 0.0]


def test_strike_dip_rhr_input_equals_dip_direction_input(tmp_path):
    by_direction = read_scanline(_write(tmp_path, HEADER + "distance,dip,dip_direction\n1,30,120\n2,80,10\n3,45,0\n"))
    # right-hand rule: dip direction = strike + 90
    by_strike = read_scanline(_write(tmp_path, HEADER + "Distance_m, Strike_deg, Dip_deg\n1,30,30\n2,-80,80\n3,270,45\n",
                                     "strike.csv"))
    assert by_strike == by_direction


def test_header_and_toml_geometry_give_the_same_scanline(tmp_path):
    from_header = read_scanline(_write(tmp_path, "# trend: 45\n# plunge: 20\n# length: 10\n# start: 1, 2, 3\n" + ROWS))
    folder = tmp_path / "toml"
    folder.mkdir()
    (folder / "line.toml").write_text("[scanline]\ntrend_deg = 45\nplunge_deg = 20.0\nlength_m = 10\n"
                                      "start_xyz_m = [1, 2, 3]\n")
    from_toml = read_scanline(_write(folder, ROWS))
    assert from_toml == from_header
    np.testing.assert_array_equal(from_toml.start_xyz_m, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(from_toml.direction, vector_from_trend_plunge(45.0, 20.0))


def test_header_and_toml_that_disagree_are_an_error(tmp_path):
    (tmp_path / "line.toml").write_text("trend_deg = 91.0\nplunge_deg = 0\nlength_m = 10\n")
    with pytest.raises(ValueError, match=r"line 1: trend = 90.0 disagrees .*trend_deg = 91"):
        read_scanline(_write(tmp_path, HEADER + ROWS))


def test_unknown_toml_key_is_named(tmp_path):
    (tmp_path / "line.toml").write_text("[scanline]\ntrend_deg = 0\nplunge_deg = 0\nlength_m = 10\nlength = 3\n")
    with pytest.raises(ValueError, match=r"line.toml: scanline.length: unknown key"):
        read_scanline(_write(tmp_path, ROWS))


@pytest.mark.parametrize("text, pattern", [
    ("", r"empty scanline file"),
    (HEADER + "distance,dip,dip_direction\n", r"line 4: no intersections"),
    (HEADER + "distance,dip,dip_direction\n1,nan,20\n", r"line 5, column 'dip': must be a finite number"),
    (HEADER + "distance,dip,dip_direction\n1,30,20\nNaN,30,20\n", r"line 6, column 'distance': must be a finite"),
    (HEADER + "distance,dip,dip_direction\n10.5,30,20\n", r"line 5, column 'distance': 10.5 m is outside"),
    (HEADER + "distance,dip,dip_direction\n3,30,20\n2,30,20\n", r"line 6, column 'distance': 2 m is less"),
    (HEADER + "distance,dip,dip_direction\n1,95,20\n", r"line 5, column 'dip': must be in \[0, 90\]"),
    (HEADER + "distance,dip,dip_direction\n1,30,north\n", r"line 5, column 'dip_direction': expected a number"),
    (HEADER + "distance,dip,dip_direction\n1,30\n", r"line 5: expected 3 columns"),
    (HEADER + "distance,dip,azimuth\n1,30,20\n", r"line 4, column 'azimuth': unknown column"),
    (HEADER + "distance,dip,dip_direction,strike\n1,30,20,3\n", r"line 4, column 'dip_direction': give exactly one"),
    ("# trend: 90\n# plunge: 0\n" + ROWS, r"scanline length is missing"),
    ("# trend: east\n# plunge: 0\n# length: 10\n" + ROWS, r"line 1, column 'trend': expected a number"),
    ("# trend: 90\n# plunge: 95\n# length: 10\n" + ROWS, r"line 2: plunge must be in"),
    ("# trend: 90\n# plunge: 0\n# length: 0\n" + ROWS, r"line 3: length must be in"),
])
def test_bad_files_raise_naming_line_and_column(tmp_path, text, pattern):
    path = _write(tmp_path, text)
    with pytest.raises(ValueError, match=pattern) as info:
        read_scanline(path)
    assert str(path) in str(info.value)


def test_scanline_arrays_are_copies_and_read_only():
    distance = np.array([1.0, 2.0])
    scanline = Scanline(distance_m=distance, dip_deg=[10, 20], dip_direction_deg=[370, -10],
                        trend_deg=-90, plunge_deg=5, length_m=3)
    distance[0] = 99.0
    assert scanline.distance_m[0] == 1.0
    assert scanline.dip_direction_deg.tolist() == [10.0, 350.0] and scanline.trend_deg == 270.0
    with pytest.raises(ValueError):
        scanline.distance_m[0] = 5.0


@pytest.mark.parametrize("kwargs, field", [
    ({"distance_m": [2.0, 1.0]}, "non-decreasing"),
    ({"distance_m": [1.0, 4.0]}, "distance_m must be in"),
    ({"dip_deg": [10, np.nan]}, "dip_deg must be finite"),
    ({"length_m": 0.0}, "length_m"),
    ({"plunge_deg": 91.0}, "plunge_deg"),
    ({"dip_deg": [10, 91]}, r"dip_deg must be in \[0, 90\]"),
])
def test_scanline_constructor_validates(kwargs, field):
    base = dict(distance_m=[1.0, 2.0], dip_deg=[10, 20], dip_direction_deg=[0, 0], trend_deg=0, plunge_deg=0,
                length_m=3.0)
    with pytest.raises(ValueError, match=field):
        Scanline(**{**base, **kwargs})
