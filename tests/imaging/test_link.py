"""Trace linking across gaps and through junctions, and extension to the image border.

Answers are set by construction: pieces cut from known straight lines, gaps and offsets of known size.
"""

import cv2
import numpy as np
import pytest

from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.link import extend_to_border, link_traces, polyline_length_px


def _pixel_chain(p0, p1):
    """(k, 2) float chain of the pixels on the segment p0 -> p1 (row, col), one per pixel step."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    n = int(np.ceil(np.abs(p1 - p0).max())) + 1
    return np.round(p0 + np.linspace(0.0, 1.0, n)[:, None] * (p1 - p0))


def _cut(p0, p1, breaks):
    """Pieces of the segment p0 -> p1 with the arc-length intervals ``breaks`` [(a, b), ...] removed."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    length = float(np.hypot(*(p1 - p0)))
    u = (p1 - p0) / length
    stops = [0.0] + [v for gap in breaks for v in gap] + [length]
    return [_pixel_chain(p0 + a * u, p0 + b * u) for a, b in zip(stops[::2], stops[1::2])]


def test_line_broken_by_known_gaps_comes_back_as_one_trace():
    pieces = _cut((50, 10), (50, 190), [(40, 48), (100, 130)])  # gaps of 8 and 30 px
    linked = link_traces(pieces, max_gap_px=35.0)
    assert len(linked) == 1
    line = linked[0]
    # it runs end to end: its extent is the original segment's, 180 px
    assert np.ptp(line[:, 1]) == pytest.approx(180.0, abs=1.0)
    assert np.all(np.diff(line[:, 1]) >= 0) or np.all(np.diff(line[:, 1]) <= 0)  # in order


def test_gap_longer_than_the_limit_stays_open():
    pieces = _cut((50, 10), (50, 190), [(40, 48), (100, 130)])
    linked = link_traces(pieces, max_gap_px=20.0)  # bridges the 8 px gap only
    # pieces [0, 40] + [48, 100] join; [130, 180] stays alone
    assert sorted(round(polyline_length_px(p)) for p in linked) == [50, 100]


def test_diagonal_line_with_gap_is_linked():
    a, b = np.array([20.0, 20.0]), np.array([170.0, 130.0])
    pieces = _cut(a, b, [(70, 95)])
    linked = link_traces(pieces, max_gap_px=30.0)
    assert len(linked) == 1


def test_two_crossing_lines_come_back_as_two_traces_not_four():
    # the skeleton of an X drawn as two Y nodes: each line's halves stop a few px from the crossing
    centre = np.array([100.0, 100.0])
    out = []
    for angle in (20.0, 65.0):  # a low-angle crossing (45 deg apart)
        u = np.array([-np.sin(np.radians(angle)), np.cos(np.radians(angle))])
        out += [_pixel_chain(centre + 4 * u, centre + 80 * u),
                _pixel_chain(centre - 4 * u, centre - 80 * u)]
    linked = link_traces(out, max_gap_px=20.0)
    assert len(linked) == 2
    for line in linked:  # each trace is one straight line through the crossing
        chord = line[-1] - line[0]
        assert np.hypot(*chord) == pytest.approx(160.0, abs=2.0)
        assert np.hypot(*(0.5 * (line[-1] + line[0]) - centre)) <= 1.5


def test_sideways_offset_pieces_are_not_linked():
    pieces = [_pixel_chain((50, 10), (50, 80)), _pixel_chain((62, 90), (62, 170))]  # 12 px apart
    assert len(link_traces(pieces, max_gap_px=30.0, max_offset_px=5.0)) == 2
    assert len(link_traces(pieces, max_gap_px=30.0, max_offset_px=15.0)) == 1


def test_pieces_meeting_at_forty_degrees_are_not_linked():
    end = np.array([50.0, 80.0])
    u = np.array([-np.sin(np.radians(40)), np.cos(np.radians(40))])
    pieces = [_pixel_chain((50, 10), end), _pixel_chain(end + 6 * u, end + 80 * u)]
    assert len(link_traces(pieces, max_gap_px=30.0, max_turn_deg=15.0)) == 2


def test_linking_never_closes_a_loop():
    # two half circles whose ends meet tangentially at both ends
    t = np.linspace(0.05, np.pi - 0.05, 60)
    top = np.column_stack([100 - 50 * np.sin(t), 100 + 50 * np.cos(t)])
    bottom = np.column_stack([100 + 50 * np.sin(t), 100 + 50 * np.cos(t)])
    linked = link_traces([top, bottom], max_gap_px=10.0, max_turn_deg=20.0, max_offset_px=5.0,
                         skip_px=0.0, reach_px=6.0)
    assert len(linked) == 1
    assert np.hypot(*(linked[0][0] - linked[0][-1])) > 1.0  # open: it starts and ends apart


def test_link_does_not_modify_its_input_and_checks_parameters():
    pieces = _cut((50, 10), (50, 190), [(40, 48)])
    before = [p.copy() for p in pieces]
    link_traces(pieces, max_gap_px=20.0)
    for p, q in zip(pieces, before):
        np.testing.assert_array_equal(p, q)
    with pytest.raises(ValueError, match="max_gap_px"):
        link_traces(pieces, max_gap_px=-1.0)
    with pytest.raises(ValueError, match="max_turn_deg"):
        link_traces(pieces, max_gap_px=10.0, max_turn_deg=120.0)


def test_end_near_the_border_is_extended_to_it_and_far_end_is_not():
    line = _pixel_chain((50, 6), (50, 70))  # 6 px from the left border, 29 px from the right
    out = extend_to_border([line], (100, 100), max_distance_px=10.0)[0]
    np.testing.assert_allclose(out[0], [50.0, -0.5])
    np.testing.assert_array_equal(out[-1], line[-1])
    assert polyline_length_px(out) == pytest.approx(70.5)


def test_end_running_nearly_along_the_border_is_extended_only_within_the_angle():
    line = _pixel_chain((10, 20), (4, 60))  # its right end heads for the top border at ~81 deg
    steep = extend_to_border([line], (100, 100), max_distance_px=35.0, max_angle_deg=45.0)[0]
    assert steep[0][1] == -0.5  # the left end points straight at the left border, 20 px away
    np.testing.assert_array_equal(steep[-1], line[-1])  # the right end is left alone
    shallow = extend_to_border([line], (100, 100), max_distance_px=35.0, max_angle_deg=85.0)[0]
    assert shallow[-1][0] == -0.5 and 60 < shallow[-1][1] < 99.5


def _broken_line_image(gap_px):
    """A dark 3-px line along row 100 from col 20 to 280, hidden over ``gap_px`` in the middle."""
    img = np.full((200, 300), 180, dtype=np.uint8)
    cv2.line(img, (20, 100), (280, 100), 60, 3, cv2.LINE_AA)
    img[90:111, 150 - gap_px // 2:150 + gap_px - gap_px // 2] = 180
    return img


def test_extract_bridges_a_thirty_pixel_hidden_stretch_only_with_linking():
    img = _broken_line_image(34)  # longer than bridge_distance_px (25), shorter than link_gap_px
    assert extract(img, m_per_px=0.01).traces.n_traces == 1
    unlinked = ExtractParams(link_gap_px=0.0)
    assert extract(img, m_per_px=0.01, params=unlinked).traces.n_traces == 2


def test_extract_returns_two_traces_for_a_low_angle_thick_crossing():
    img = np.full((240, 320), 180, dtype=np.uint8)
    for angle in (20.0, 60.0):  # 40 deg apart, 5 px wide: the skeleton makes two Y nodes
        d = 140 * np.array([np.cos(np.radians(angle)), -np.sin(np.radians(angle))])
        p0, p1 = np.round(np.array([160.0, 120.0]) - d), np.round(np.array([160.0, 120.0]) + d)
        cv2.line(img, tuple(int(v) for v in p0), tuple(int(v) for v in p1), 60, 5, cv2.LINE_AA)
    traces = extract(img, m_per_px=0.01, joint_width_px=5.0).traces
    assert traces.n_traces == 2


@pytest.mark.parametrize("field, value", [("link_gap_px", -1.0), ("link_offset_px", float("nan")),
                                          ("link_turn_deg", 120.0), ("link_reach_px", 0.0),
                                          ("border_extend_px", -2.0)])
def test_bad_link_settings_are_refused_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        ExtractParams(**{field: value})
