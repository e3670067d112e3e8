"""Bad input raises ValueError naming the field."""

import numpy as np
import pytest

from rockmass.blockgen import JointSet, build, circle, polygon_excavation

from ._fixtures import square


@pytest.mark.parametrize("spacing", [0.0, -1.0, float("nan")])
def test_non_positive_spacing_is_refused(spacing):
    with pytest.raises(ValueError, match="spacing_m"):
        JointSet(0, spacing)


def test_excavation_partly_outside_the_domain_is_refused():
    with pytest.raises(ValueError, match=r"excavations\[0\].*partly"):
        build(square(1.0), [JointSet(0, 0.2)], excavations=[circle((0.95, 0.5), 0.1)])


def test_excavation_wholly_outside_the_domain_is_refused():
    with pytest.raises(ValueError, match=r"excavations\[0\].*wholly"):
        build(square(1.0), [JointSet(0, 0.2)], excavations=[circle((5, 5), 0.1)])


def test_degenerate_polygons_are_refused():
    with pytest.raises(ValueError, match="domain_xy_m"):
        build([(0, 0), (1, 1), (2, 2)], [JointSet(0, 0.2)])
    with pytest.raises(ValueError, match="xy_m"):
        polygon_excavation([(0, 0), (1, 1), (1, 0), (0, 1)])


def test_nan_traces_are_refused():
    segs = np.array([[[0.1, 0.1], [0.9, np.nan]]])
    with pytest.raises(ValueError, match="traces"):
        build(square(1.0), traces=segs)


def test_a_set_with_no_joints_in_the_domain_is_refused():
    # spacing larger than the domain, origin placing the only line outside it
    with pytest.raises(ValueError, match=r"joint_sets\[1\]"):
        build(square(1.0), [JointSet(0, 0.2), JointSet(0, 10.0, origin_xy_m=(0, 5))])


def test_min_edge_larger_than_the_blocks_is_refused():
    with pytest.raises(ValueError, match="min_edge_m"):
        build(square(1.0), [JointSet(0, 0.1), JointSet(90, 0.1)], min_edge_m=0.5)


def test_unknown_dangling_choice_lists_the_choices():
    with pytest.raises(ValueError, match="dangling.*glued"):
        build(square(1.0), [JointSet(0, 0.1)], dangling="extend")
