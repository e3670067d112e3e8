"""The learned detector on coarser grids (docs/imaging.md §3.4, imaging.grid_levels).

Oracles: the same face photographed with four times the pixels per side (enlarged) is the same
face, so the detector, allowed to look at it on a coarser grid, should find about what it finds
on the photo as it was taken, and much more than on the enlarged grid alone; the geometry of
moving polylines between grids and of coarsening a mask is exact."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rockmass.imaging import grid_levels
from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.metrics import trace_accuracy
from rockmass.imaging.synthetic import synthetic_face


def test_polylines_move_between_grids_by_pixel_centres():
    chain = np.array([[0.0, 0.0], [9.0, 19.0]])
    fine = grid_levels.to_grid([chain], (10, 20), (40, 80))[0]
    assert fine.tolist() == [[1.5, 1.5], [37.5, 77.5]]  # centre of coarse (0, 0) = centre of 4x4
    back = grid_levels.to_grid([fine], (40, 80), (10, 20))[0]
    np.testing.assert_allclose(back, chain)


def test_a_coarse_pixel_is_in_the_mask_when_most_of_it_was():
    grey = np.zeros((8, 8), np.float32)
    mask = np.zeros((8, 8), bool)
    mask[:, :4] = True  # left half
    mask[0, 4] = True  # a quarter of the coarse pixel (0, 2): out
    image, coarse, shape = grid_levels.coarsen(grey, mask, 2)
    assert shape == (4, 4) and image.shape == (4, 4)
    assert coarse[:, :2].all() and not coarse[:, 2:].any()
    assert grid_levels.coarsen(grey, None, 4)[1] is None


def test_levels_that_leave_too_few_pixels_are_not_tried():
    assert grid_levels.usable_levels((2, 4), (512, 600)) == (2, 4)
    assert grid_levels.usable_levels((2, 4), (255, 600)) == (2,)
    assert grid_levels.usable_levels((2, 4), (100, 600)) == ()


@pytest.mark.parametrize("value", [(1,), (2, 2), (2.0,), (True,), "2", (0, 2)])
def test_bad_levels_are_refused_by_name(value):
    with pytest.raises(ValueError, match="learned_levels"):
        ExtractParams(learned_levels=value)


def test_levels_given_as_a_list_are_kept_sorted():
    assert ExtractParams(learned_levels=[4, 2]).learned_levels == (2, 4)
    assert ExtractParams(learned_levels=[]).learned_levels == ()


@pytest.fixture(scope="module")
def enlarged_face():
    """A moderate face as taken (300 x 450 px, 2 cm/px) and the same enlarged 4 times."""
    face = synthetic_face("moderate", seed=3, shape_px=(300, 450), m_per_px=0.02)
    big = cv2.resize(face.image, (1800, 1200), interpolation=cv2.INTER_CUBIC)
    return face, big


def _f1(face, image, m_per_px, **settings):
    result = extract(image, m_per_px=m_per_px, params=ExtractParams(detector="learned", **settings))
    return trace_accuracy(result.traces, face.truth, m_per_px=0.02).f1, result


def test_an_enlarged_photo_is_read_on_a_coarser_grid(enlarged_face):
    face, big = enlarged_face
    as_taken, _ = _f1(face, face.image, 0.02)
    enlarged_alone, _ = _f1(face, big, 0.005, learned_levels=())
    enlarged, result = _f1(face, big, 0.005)
    record = result.learned_levels
    assert record["levels"] == [1, 2, 4] and record["kept"] > 1
    # the working grid finds a few clean pieces of the wide joints, the coarser one most of them
    assert max(record["length"][1:]) > 3 * record["length"][0]
    assert enlarged >= enlarged_alone + 0.1
    assert enlarged >= as_taken - 0.1
    assert result.summary()["learned_levels"]["kept"] == record["kept"]
    assert any("coarsened" in note for note in result.warnings)
    assert result.joint_width_source.endswith(f"grid coarsened {record['kept']}x")


def test_auto_reads_the_learned_detector_on_the_same_grids(enlarged_face):
    import time

    face, big = enlarged_face
    learned = extract(big, m_per_px=0.005, params=ExtractParams(detector="learned"))
    t0 = time.perf_counter()
    auto = extract(big, m_per_px=0.005, params=ExtractParams(detector="auto"))
    wall = time.perf_counter() - t0
    assert dict(auto.learned_levels) == dict(learned.learned_levels)
    # two threads at most: the steps' times, summed over both, cannot exceed twice the wall time
    # (they did while a queued task's clock ran from the moment it was queued)
    assert sum(auto.timings_s.values()) <= 2.0 * wall
    assert extract(big, m_per_px=0.005, params=ExtractParams(detector="ridge")).learned_levels is None


def test_a_coarser_grid_is_recorded_in_a_json_summary_and_its_debug_maps_fit_the_grid(enlarged_face):
    import json

    _, big = enlarged_face
    result = extract(big, m_per_px=0.005, params=ExtractParams(detector="learned"), debug=True)
    assert result.learned_levels["kept"] > 1
    json.dumps(result.summary(), allow_nan=False)
    work = result.scale.work_shape_px
    assert all(image.shape[:2] == work for image in result.debug.values())


def test_levels_can_be_set_in_a_config_file():
    from rockmass.config import ImagingConfig

    assert ImagingConfig(params={"learned_levels": []}).params["learned_levels"] == []
    assert ImagingConfig(params={"learned_levels": [2, 4]}).params["learned_levels"] == [2, 4]
    with pytest.raises(ValueError, match="learned_levels"):
        ImagingConfig(params={"learned_levels": [1]})
