"""SHARP TURNS does not depend on where the traces lie: a turn of exactly the limit is at it.

Oracle: the turns of traces through pixel centres, decided in exact integer arithmetic (a turn
beyond 90° is a negative dot product of integer steps), the label fractopo's rule
(``deg_angle > threshold_angle``) gives without rounding.
"""

import numpy as np
import pytest

from rockmass.dfn import TraceMap, validate_traces

TAU = 1e-3
PIXEL_M = 0.05  # the drone tiles' ground sampling distance
ROWS = 4000
SHIFTS = [(0.0, 0.0), (5e5, 9e6), (-3.3e6, 1.7e7)]  # face frame, UTM-like map corners
STEPS = np.array([(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)])


def face_xy(pixels):
    """Pixel centres (column, row) in the face frame, as extraction writes them."""
    pixels = np.asarray(pixels, dtype=float)
    return np.column_stack([(pixels[:, 0] + 0.5) * PIXEL_M, (ROWS - pixels[:, 1] - 0.5) * PIXEL_M])


def sharp(polylines, shift=(0.0, 0.0)):
    tm = TraceMap.from_polylines([np.asarray(p, dtype=float) + np.asarray(shift) for p in polylines])
    return [("SHARP TURNS" in e) for e in validate_traces(tm, snap_tolerance_m=TAU).errors()]


def exactly_sharp(pixels) -> bool:
    """fractopo's rule in exact arithmetic on integer pixel steps: a zero-length segment or chord, or
    a segment more than 90° from the previous one or from the chord."""
    step = np.diff(np.asarray(pixels), axis=0)
    chord = step.sum(axis=0)
    if len(pixels) < 3:
        return False
    return bool(not chord.any() or not step.any(axis=1).all() or (step @ chord < 0).any()
                or (np.einsum("ij,ij->i", step[1:], step[:-1]) < 0).any())


STAIRCASES = {  # (column, row) pixel paths; every turn of the first four is exactly 90°
    "axis staircase": [(0, 0), (1, 0), (1, 1), (2, 1), (2, 2), (3, 2)],
    "diagonal zig-zag": [(10, 10), (11, 11), (12, 10), (13, 11), (14, 10)],
    "segment square to its chord": [(20, 0), (21, 0), (21, 3), (20, 3)],
    "long steps": [(7, 40), (19, 40), (19, 52), (31, 52), (31, 64)],
    "doubles back": [(0, 30), (5, 30), (1, 31)],  # control: a turn of about 166°
}


@pytest.mark.parametrize("shift", SHIFTS[1:])
def test_exact_90_degree_staircase_is_labelled_the_same_anywhere(shift):
    polylines = [face_xy(p) for p in STAIRCASES.values()]
    expected = [exactly_sharp(p) for p in STAIRCASES.values()]
    assert expected == [False, False, False, False, True]
    assert sharp(polylines) == expected
    assert sharp(polylines, shift) == expected


@pytest.mark.parametrize("shift", SHIFTS)
@pytest.mark.parametrize("segment_m", [PIXEL_M, 1.0])
@pytest.mark.parametrize("turn_deg, flagged", [(90.01, True), (89.99, False), (90.0, False)])
def test_turns_near_the_limit_keep_their_label(shift, segment_m, turn_deg, flagged):
    a = np.radians(turn_deg)
    base = np.array([[0.0, 0.0], [segment_m, 0.0], [segment_m * (1 + np.cos(a)), segment_m * np.sin(a)]])
    rotated = base @ np.array([[0.6, 0.8], [-0.8, 0.6]])  # the same turn, along no axis
    assert sharp([base, rotated], shift) == [flagged, flagged]


def random_staircases(rng, n):
    """Pixel paths of 8-connected steps that mostly keep their direction (turns of 45°, 90°, 135°)."""
    paths = []
    for _ in range(n):
        direction, path = rng.integers(8), [rng.integers(0, 2000, 2)]
        for _ in range(rng.integers(2, 12)):
            direction = (direction + rng.choice([-2, -1, 0, 0, 0, 1, 2])) % 8
            path.append(path[-1] + STEPS[direction])
        paths.append(np.array(path))
    return paths


def test_random_pixel_staircases_count_the_same_in_face_and_map_frames():
    paths = random_staircases(np.random.default_rng(0), 1500)  # seed 0: a fixed set
    expected = [exactly_sharp(p) for p in paths]
    steps = [np.diff(p, axis=0) for p in paths]
    n_right_angles = sum(int((np.einsum("ij,ij->i", s[1:], s[:-1]) == 0).sum()) for s in steps)
    assert n_right_angles > 1000 and 0 < sum(expected) < len(paths)  # many turns at the limit
    polylines = [face_xy(p) for p in paths]
    labels = {shift: sharp(polylines, shift) for shift in SHIFTS}
    for shift in SHIFTS:
        assert labels[shift] == expected, shift
    assert len({sum(v) for v in labels.values()}) == 1
