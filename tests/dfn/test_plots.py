"""Rose diagram geometry and the figure writers."""

import numpy as np
import pytest

from rockmass.dfn.plots import plot_trace_map, rose_diagram, rose_petals


def test_rose_petal_areas_are_proportional_to_length():
    angles = np.array([5.0, 5.0, 95.0])
    lengths = np.array([1.0, 2.0, 1.0])
    edges, radii = rose_petals(angles, lengths, bin_deg=10.0)
    area = radii**2  # petal area is proportional to radius squared for equal bin widths
    assert area[0] / area[9] == pytest.approx(3.0)  # 0-10° holds 3 m, 90-100° holds 1 m
    assert area.sum() == pytest.approx(2.0)  # each half of the rose holds the whole length once


def test_rose_is_axial():
    edges, radii = rose_petals([30.0, 170.0], [1.0, 1.0], bin_deg=15.0)
    half = radii.size // 2
    assert np.array_equal(radii[:half], radii[half:])
    assert rose_petals([210.0], [1.0])[1].tolist() == rose_petals([30.0], [1.0])[1].tolist()


def test_bad_bin_width_is_refused():
    with pytest.raises(ValueError, match="bin_deg"):
        rose_petals([10.0], [1.0], bin_deg=7.0)


def test_figures_are_written(tmp_path):
    from rockmass.dfn import TraceMap

    trace_map = TraceMap.from_segments(np.array([[0, 0, 1, 1], [0, 1, 1, 0.0]]))
    rose_diagram([45.0, 135.0], [1.0, 1.0], tmp_path / "rose.png", set_means_deg=[45.0, 135.0])
    plot_trace_map(trace_map, tmp_path / "map.png", set_ids=np.array([0, 1]))
    assert (tmp_path / "rose.png").stat().st_size > 5000
    assert (tmp_path / "map.png").stat().st_size > 5000
