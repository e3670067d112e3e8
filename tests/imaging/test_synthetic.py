"""Synthetic faces: reproducible, faithful to the requested sets, and harder at harder levels."""

import numpy as np
import pytest

from rockmass.dfn import read_traces
from rockmass.imaging import DIFFICULTIES, JointSetSpec, save_synthetic_face, synthetic_face
from rockmass.imaging.frame import uv_to_rc

SMALL = dict(shape_px=(300, 450), m_per_px=0.02)


def test_same_seed_gives_the_same_face():
    a = synthetic_face("moderate", seed=5, **SMALL)
    b = synthetic_face("moderate", seed=5, **SMALL)
    assert np.array_equal(a.image, b.image)
    assert np.array_equal(a.truth.xy_m, b.truth.xy_m)
    c = synthetic_face("moderate", seed=6, **SMALL)
    assert not np.array_equal(a.image, c.image)


def test_truth_lies_inside_the_image():
    face = synthetic_face("easy", seed=1, **SMALL)
    h, w = face.image.shape
    xy = face.truth.xy_m
    assert xy.min() >= -1e-9
    assert xy[:, 0].max() <= w * face.m_per_px + 1e-9
    assert xy[:, 1].max() <= h * face.m_per_px + 1e-9


def test_set_mean_angles_match_the_specification():
    # two tight sets: the length-weighted axial mean of each set's traces is within 3 degrees
    sets = (JointSetSpec(30.0, 200.0, 1.5, 0.3, 4.0), JointSetSpec(120.0, 200.0, 1.5, 0.3, 4.0))
    face = synthetic_face("easy", seed=2, sets=sets, shape_px=(500, 500), m_per_px=0.02)
    seg = face.truth.segments()
    index = face.truth.segment_trace_index()
    set_of_segment = face.truth.attributes["set"][index]
    angle = np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0])
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    for set_id, spec in enumerate(sets, start=1):
        sel = set_of_segment == set_id
        assert sel.sum() > 20
        doubled = np.sum(length[sel] * np.exp(2j * angle[sel]))
        mean = np.degrees(np.angle(doubled) / 2) % 180
        assert abs((mean - spec.angle_deg + 90) % 180 - 90) < 3.0


def _contrast_to_noise(face) -> float:
    """(rock median - median on wide trace centre lines) / robust sd of the rock."""
    image = face.image.astype(float)
    h, _ = image.shape
    wide = face.truth.attributes["width_px"] >= 3
    on_line = []
    for i in np.flatnonzero(wide):
        poly = face.truth.polyline(i)
        t = np.linspace(0, 1, 50)[:, None]
        pts = poly[0] + t * (poly[-1] - poly[0]) if poly.shape[0] == 2 else poly
        rc = np.round(uv_to_rc(pts, h, face.m_per_px)).astype(int)
        ok = (rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < image.shape[1])
        on_line.extend(image[rc[ok, 0], rc[ok, 1]])
    rock = np.median(image)
    spread = 1.4826 * np.median(np.abs(image - rock))
    return (rock - np.median(on_line)) / spread


def test_traces_are_darker_than_the_rock_and_harder_levels_hide_them_more():
    cnr = [_contrast_to_noise(synthetic_face(level, seed=3, **SMALL)) for level in DIFFICULTIES]
    assert cnr[0] > 2.0  # easy: traces stand well clear of the rock
    assert cnr[0] > cnr[1] > cnr[2] > 0.0


def test_saved_face_reads_back(tmp_path):
    import cv2

    face = synthetic_face("hard", seed=4, **SMALL)
    paths = save_synthetic_face(face, tmp_path)
    assert np.array_equal(cv2.imread(str(paths["image"]), cv2.IMREAD_GRAYSCALE), face.image)
    truth = read_traces(paths["truth"])
    assert np.array_equal(truth.xy_m, face.truth.xy_m)
    assert np.array_equal(truth.attributes["set"], face.truth.attributes["set"])


@pytest.mark.parametrize("kwargs, field", [({"difficulty": "insane"}, "difficulty"),
                                           ({"m_per_px": 0.0}, "m_per_px"),
                                           ({"shape_px": (8, 8)}, "shape_px")])
def test_bad_arguments_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        synthetic_face(**{"difficulty": "easy", **kwargs})


def _photo(shape=(300, 450), seed=11):
    """A stand-in rock photograph: smooth blotches and grain around grey 110 (RGB, uint8)."""
    import cv2

    rng = np.random.default_rng(seed)
    grey = 110 + 25 * cv2.GaussianBlur(rng.standard_normal(shape), (0, 0), 6) * 6 \
        + 6 * rng.standard_normal(shape)
    grey = np.clip(grey, 20, 235).astype(np.uint8)
    return np.dstack([grey] * 3)


def test_joints_on_a_photo_are_the_synthetic_face_network_and_leave_the_rest_of_the_photo():
    from rockmass.imaging import joints_on_photo
    from rockmass.imaging.metrics import render_traces

    photo = _photo()
    face = joints_on_photo(photo, seed=5, m_per_px=0.02)
    plain = synthetic_face("moderate", seed=5, **SMALL)
    assert np.array_equal(face.truth.xy_m, plain.truth.xy_m)       # the same network, seed for seed
    for name in ("width_px", "set"):                                # drawn as wide, set by set
        assert np.array_equal(face.truth.attributes[name], plain.truth.attributes[name])
    again = joints_on_photo(photo, seed=5, m_per_px=0.02)
    assert np.array_equal(face.image, again.image)
    import cv2

    lines = render_traces(face.truth, photo.shape[:2], 0.02)
    far = cv2.distanceTransform(np.where(lines, 0, 255).astype(np.uint8), cv2.DIST_L2, 5) > 12
    difference = face.image[far].astype(float) - photo[..., 0][far]
    assert abs(difference.mean()) < 1.0 and np.abs(difference).mean() < 4.0  # JPEG only
    # on the centre lines of the wide joints (lines overlap without adding: darkness is at most 1,
    # and hidden stretches are a minority), darker by the style's contrast / 150 of the photo's grey
    wide = face.truth.subset(np.asarray(face.truth.attributes["width_px"]) >= 4)
    on = render_traces(wide, photo.shape[:2], 0.02)
    ratio = np.median(face.image[on] / np.maximum(photo[..., 0][on].astype(float), 1.0))
    assert ratio == pytest.approx(1.0 - DIFFICULTIES["moderate"].contrast / 150.0, abs=0.05)


@pytest.mark.parametrize("photo", [np.zeros((8, 40), np.uint8), np.zeros((40, 40), np.float32),
                                   np.zeros((40, 40, 2), np.uint8)])
def test_joints_on_photo_refuses_what_is_not_a_photo(photo):
    from rockmass.imaging import joints_on_photo

    with pytest.raises(ValueError, match="photo"):
        joints_on_photo(photo, seed=1, m_per_px=0.02)


def test_a_face_drawn_from_given_traces_keeps_them_as_its_truth():
    from rockmass.dfn import TraceMap
    from rockmass.imaging.metrics import render_traces

    given = TraceMap.from_segments([[1.0, 1.0, 8.0, 5.0], [2.0, 5.5, 7.0, 0.5]], {"set": [0, 3]})
    face = synthetic_face("easy", seed=2, traces=given, **SMALL)
    assert np.array_equal(face.truth.xy_m, given.xy_m)
    assert np.asarray(face.truth.attributes["set"]).tolist() == [0, 3]
    on = render_traces(given, face.image.shape, SMALL["m_per_px"])
    assert np.median(face.image[on]) < np.median(face.image[~on]) - 40   # easy: 80 grey levels darker
    other = synthetic_face("easy", seed=2, **SMALL)                      # same seed, its own network
    assert not np.array_equal(other.truth.xy_m, given.xy_m)
