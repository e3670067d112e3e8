"""Box counting: counts against independent oracles, the fit, offsets, masks and images."""

import numpy as np
import pytest

from rockmass.fractal import box_count, divisors, fit_loglog, grid_offsets, rasterize_traces
from tests.fractal._fixtures import (naive_line_statistics, naive_occupied_boxes,
                                     naive_offset_boxes, random_network, shapely_crossed_boxes,
                                     shapely_face_boxes)


def test_360_has_24_divisors():
    assert divisors(360).tolist() == [1, 2, 3, 4, 5, 6, 8, 9, 10, 12, 15, 18, 20, 24, 30, 36, 40,
                                      45, 60, 72, 90, 120, 180, 360]


def test_raster_counts_match_numpy_reshape_oracle():
    image = rasterize_traces(random_network(80, seed=1), grid=360)
    result = box_count(image, n_offsets=1)
    expected = [naive_occupied_boxes(image, int(s)) for s in result.sizes_px]
    assert result.counts.tolist() == expected


def test_offset_counts_match_rolled_image_oracle():
    from rockmass.fractal.boxcount import _count_raster_mask, _raster_shifts

    image = rasterize_traces(random_network(40, seed=2), grid=120)
    sizes = divisors(120)
    offsets = grid_offsets(5)
    counts = _count_raster_mask(image, sizes, offsets)
    shifts = _raster_shifts(sizes, offsets)  # (size, offset, (column, row)) in pixels
    assert shifts[sizes >= 8].any()
    for a, s in enumerate(sizes):
        for b in range(offsets.shape[0]):
            expected = naive_offset_boxes(image, int(s), int(shifts[a, b, 1]), int(shifts[a, b, 0]))
            assert counts[a, b] == expected


@pytest.mark.parametrize("method", ["raster", "vector"])
@pytest.mark.parametrize("angle", [0.0, 45.0, 90.0, 135.0])
def test_every_shifted_grid_keeps_a_straight_line_at_dimension_1(method, angle):
    """Closed form: a segment spanning its frame at a multiple of 45° crosses a number of boxes
    proportional to 1/size on every grid shifted by a fixed fraction of the box, so D = 1. Whole-
    pixel shifts would break that (0.84-1.00 on an image); traces are shifted exactly."""
    from rockmass.fractal import reference

    result = box_count(reference.straight_line(angle), method=method, n_offsets=8)
    assert np.allclose(result.offset_dimensions, 1.0, atol=1e-9)


def test_vector_count_matches_shapely_box_intersection():
    seg = random_network(25, seed=3, extent=1.0)
    result = box_count(seg, method="vector", grid=12, sizes_px=[1, 2, 3], fit_range_px=(1, 3),
                       n_offsets=1)
    frame = result.frame
    for size_px, count in zip(result.sizes_px, result.counts):
        box = frame["side_m"] * size_px / 12
        expected = shapely_crossed_boxes(seg, frame["x0_m"], frame["y0_m"], box, int(12 / size_px))
        assert count == expected


def test_shifted_vector_grids_match_shapely():
    """Shifted (cyclic) grids against shapely boxes on the shifted, one-box-larger covering."""
    from rockmass.fractal import _kernels

    seg = random_network(20, seed=17, extent=1.0)
    side = 1.3  # a frame larger than the network, anchored at the origin
    shifted = seg + 0.1
    for n in (4, 6):
        d = side / n
        for fx, fy in ((0.3, 0.7), (0.55, 0.1)):
            counts = np.zeros((1, 1), dtype=np.int64)
            totals = np.zeros_like(counts)
            _kernels.count_crossed_boxes(shifted, side, np.array([d]), np.array([[fx, fy]]), 1 << 24,
                                         counts, totals)
            expected = shapely_crossed_boxes(shifted, 0.0, 0.0, d, n + 1, shift=(fx * d, fy * d),
                                             fold=True)
            assert counts[0, 0] == expected and totals[0, 0] == n * n


def test_vector_count_at_sizes_that_do_not_divide_the_side_matches_shapely():
    from rockmass.fractal import _kernels

    seg = random_network(20, seed=18, extent=1.0) + 0.05
    side = 1.1
    d = side / 3.7  # 4 boxes per axis, the last one partial
    counts = np.zeros((1, 1), dtype=np.int64)
    totals = np.zeros_like(counts)
    _kernels.count_crossed_boxes(seg, side, np.array([d]), np.zeros((1, 2)), 1 << 24, counts, totals)
    assert counts[0, 0] == shapely_crossed_boxes(seg, 0.0, 0.0, d, 4)
    assert totals[0, 0] == 16


def test_face_boxes_match_shapely_polygon_overlap():
    """The face count (boxes meeting a concave polygon) against shapely areas."""
    ring = np.array([[0.5, 0.5], [9.0, 1.0], [5.0, 4.0], [9.5, 9.0], [1.0, 8.0]])
    seg = random_network(60, seed=19)
    for method in ("raster", "vector"):
        result = box_count(seg, method=method, mask=ring, grid=36, n_offsets=1)
        f = result.frame
        for size, face in zip(result.sizes_px[:6], result.face_counts[:6]):
            box = f["side_m"] * size / 36
            n = int(round(36 / size))
            assert face == shapely_face_boxes(ring, f["x0_m"], f["y0_m"], box, n)


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_vector_and_supercover_raster_agree_exactly_at_zero_offset(seed):
    """Two counting paths (pixel marks + bit-packed OR windows, and per-size traversal) that share the
    traversal rule; each is checked against shapely separately above."""
    seg = random_network(200, seed=seed)
    raster = box_count(seg, method="raster", n_offsets=1)
    vector = box_count(seg, method="vector", n_offsets=1)
    assert np.array_equal(raster.counts, vector.counts)
    assert raster.dimension == vector.dimension


def test_bresenham_rule_counts_fewer_or_equal_boxes_at_one_pixel():
    seg = random_network(200, seed=7)
    sc = box_count(seg, line_rule="supercover", n_offsets=1)
    br = box_count(seg, line_rule="bresenham", n_offsets=1)
    assert br.counts[0] < sc.counts[0]  # 8-connected lines skip the pixels a line only clips
    assert abs(br.dimension - sc.dimension) < 0.1


@pytest.mark.parametrize("shift, scale", [((1000.25, -37.5), 1.0), ((0.0, 0.0), 7.3),
                                          ((-5e4, 2e4), 0.013)])
def test_vector_count_is_invariant_to_translation_and_scale(shift, scale):
    seg = random_network(150, seed=8)
    moved = seg * scale + np.tile(shift, 2)
    a = box_count(seg, method="vector", n_offsets=3)
    b = box_count(moved, method="vector", n_offsets=3)
    assert np.array_equal(a.counts, b.counts)
    assert b.dimension == pytest.approx(a.dimension, abs=1e-12)
    assert b.p21_per_m == pytest.approx(a.p21_per_m / scale, rel=1e-9)


def test_vector_counting_works_at_sizes_too_fine_for_a_mark_array():
    seg = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0]])
    result = box_count(seg, method="vector", grid=360, sizes_px=[0.01, 0.02, 0.04],
                       fit_range_px=(0.01, 0.04), n_offsets=1)  # 36,000^2 boxes at the smallest
    assert result.counts.tolist() == [2 * 36000 - 1, 2 * 18000 - 1, 2 * 9000 - 1]


def test_fit_matches_numpy_polyfit_and_textbook_stderr():
    rng = np.random.default_rng(9)
    sizes = np.array([1, 2, 3, 4, 6, 8, 12, 16], dtype=float)
    counts = 500 * sizes**-1.4 * np.exp(rng.normal(0, 0.05, sizes.size))
    fit = fit_loglog(sizes, counts)
    x, y = -np.log(sizes), np.log(counts)
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    stderr = np.sqrt(resid @ resid / (x.size - 2) / np.sum((x - x.mean()) ** 2))
    assert fit.dimension == pytest.approx(slope, rel=1e-12)
    assert fit.stderr == pytest.approx(stderr, rel=1e-10)
    assert fit.ci95[0] < fit.dimension < fit.ci95[1]
    assert fit.ci95[1] - fit.dimension == pytest.approx(2.4469 * stderr, rel=1e-4)  # t(0.975, 6)


def test_offset_slopes_are_bit_for_bit_those_of_the_full_fit():
    """The slopes of all offsets at once equal fit_loglog's slope column by column (seed 42)."""
    from rockmass.fractal.fit import loglog_slopes

    rng = np.random.default_rng(42)
    sizes = divisors(360)[:21].astype(float)
    counts = np.maximum(1.0, np.round(1e5 * sizes[:, None] ** -rng.uniform(1.0, 2.0, 8)
                                      * np.exp(rng.normal(0, 0.05, (sizes.size, 8)))))
    expected = [fit_loglog(sizes, counts[:, b]).dimension for b in range(8)]
    assert loglog_slopes(sizes, counts).tolist() == expected


def test_default_fit_range_stops_at_a_quarter_of_the_grid():
    result = box_count(random_network(100, seed=10), n_offsets=1)
    assert result.fit_range_px == (1.0, 90.0)
    assert result.sizes_px[result.in_fit].max() == 90
    assert result.local_slopes.size == result.sizes_px.size - 1


@pytest.mark.parametrize("method", ["raster", "vector"])
def test_shifted_grids_keep_exact_answers_of_frame_filling_sets(method):
    """Cyclic shifts add no partial boxes: a filled square stays 2 and a full-width line 1."""
    from rockmass.fractal import reference

    square = box_count(reference.filled_square(360), n_offsets=8)
    assert np.allclose(square.offset_dimensions, 2.0, atol=1e-12)
    line = box_count(np.array([[0.0, 3.3, 10.0, 3.3]]), method=method, n_offsets=8)
    assert np.allclose(line.offset_dimensions, 1.0, atol=1e-12)


def test_vector_offset_counts_match_raster_offsets_on_a_divisor_grid():
    """Raster shifts are whole pixels: give the vector counter the same pixel shifts."""
    from rockmass.fractal import _kernels
    from rockmass.fractal.boxcount import _count_raster_mask

    seg = random_network(60, seed=16, extent=1.0)
    image = rasterize_traces(seg, grid=60)
    sizes = divisors(60)[1:-1]
    shift_px = np.array([[2.0, 5.0]])
    raster = np.zeros((sizes.size, 1), dtype=np.int64)
    for a, s in enumerate(sizes):  # whole-pixel shift (column 2, row 5 from the top) per size
        off = np.array([[(2 % s + 1e-9) / s, (5 % s + 1e-9) / s]])
        raster[a] = _count_raster_mask(image, np.array([s]), off)[0]
    x0, y0 = seg[:, 0::2].min(), seg[:, 1::2].min()
    side = max(np.ptp(seg[:, 0::2]), np.ptp(seg[:, 1::2]))
    rel = seg.copy()
    rel[:, 0::2] -= x0 - 0.5 * (side - np.ptp(seg[:, 0::2]))
    rel[:, 1::2] -= y0 - 0.5 * (side - np.ptp(seg[:, 1::2]))
    vector = np.zeros((sizes.size, 1), dtype=np.int64)
    totals = np.zeros_like(vector)
    for a, s in enumerate(sizes):
        d = side * s / 60
        # image rows run down: a row shift of 5 px from the top is a shift of -5 px (mod s) in v
        off = np.array([[shift_px[0, 0] / s % 1.0, (-shift_px[0, 1] / s) % 1.0]])
        c = np.zeros((1, 1), dtype=np.int64)
        t = np.zeros((1, 1), dtype=np.int64)
        _kernels.count_crossed_boxes(rel, side, np.array([d]), off, 1 << 24, c, t)
        vector[a] = c[0, 0]
    assert np.array_equal(raster, vector)


def test_offset_spread_is_reported_and_first_offset_is_zero():
    result = box_count(random_network(100, seed=11), n_offsets=6)
    assert result.offset_dimensions.size == 6
    assert result.offset_dimensions[0] == result.dimension
    assert result.offset_spread > 0
    assert result.offset_range[0] <= result.dimension <= result.offset_range[1]


def test_face_completely_covered_has_dimension_2_whatever_its_outline():
    yy, xx = np.mgrid[0:360, 0:360]
    disc = ((yy - 180.0) ** 2 + (xx - 170.0) ** 2 < 150.0**2).astype(np.uint8)
    raw = box_count(disc, n_offsets=1, mask=None)
    corrected = box_count(disc, n_offsets=1, mask=disc)
    assert raw.dimension < 1.99  # empty corners flatten the curve
    assert corrected.dimension == pytest.approx(2.0, abs=1e-12)


def test_vector_and_raster_face_counts_agree_with_a_polygon_mask():
    seg = random_network(150, seed=12)
    mask = np.array([[1.0, 1.0], [9.0, 2.0], [8.0, 9.5], [2.5, 7.0]])
    raster = box_count(seg, method="raster", mask=mask, n_offsets=1)
    vector = box_count(seg, method="vector", mask=mask, n_offsets=1)
    assert np.array_equal(raster.face_counts, vector.face_counts)
    assert np.array_equal(raster.counts, vector.counts)


def test_traces_outside_the_mask_do_not_count():
    inside = np.array([[1.0, 1.0, 3.0, 3.0]])
    outside = np.array([[6.0, 6.0, 9.0, 8.0]])
    mask = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]])
    a = box_count(inside, mask=mask, n_offsets=1)
    b = box_count(np.vstack([inside, outside]), mask=mask, n_offsets=1)
    assert np.array_equal(a.counts, b.counts)


def test_p21_is_length_over_window_area():
    seg = np.array([[0.0, 0.5, 2.0, 0.5], [1.0, 0.0, 1.0, 2.0]])
    result = box_count(seg, window=(0, 0, 2, 2), n_offsets=1)
    assert result.area_m2 == pytest.approx(4.0)
    assert result.p21_per_m == pytest.approx(4.0 / 4.0)


def test_thick_lines_are_skeletonised_and_reported():
    import cv2

    seg = random_network(30, seed=13, extent=350.0) + 5.0
    thin = np.zeros((360, 360), np.uint8)
    thick = np.zeros((360, 360), np.uint8)
    for x0, y0, x1, y1 in seg.round().astype(int):
        cv2.line(thin, (x0, y0), (x1, y1), 1, 1)
        cv2.line(thick, (x0, y0), (x1, y1), 1, 5)
    r_thin = box_count(thin, n_offsets=1)
    r_thick = box_count(thick, n_offsets=1)
    r_never = box_count(thick, n_offsets=1, skeletonize="never")
    assert not r_thin.skeletonized and r_thick.skeletonized
    assert any("skeletonised" in n for n in r_thick.notes)
    assert abs(r_thick.dimension - r_thin.dimension) < 0.05
    assert r_never.dimension > r_thin.dimension + 0.05  # 5-px lines bias D high (REFERENCE §1)


def _any_shifts(sizes, rng, k=5):
    """Pixel shifts (rows, cols) ``(n_sizes, k + 3)``: the corners 0 and size - 1, then random."""
    rows = [np.r_[0, s - 1, 0, rng.integers(0, s, k)] for s in sizes]
    cols = [np.r_[0, s - 1, s - 1, rng.integers(0, s, k)] for s in sizes]
    return np.array(rows), np.array(cols)


def _reference_images():
    from rockmass.fractal import reference

    return [("sierpinski_triangle", reference.sierpinski_triangle(7)),
            ("sierpinski_carpet", reference.sierpinski_carpet(4)),
            ("cantor_dust", reference.cantor_dust(4)),
            ("vicsek", reference.vicsek(4)),
            ("triangle in 360", reference.embed(reference.sierpinski_triangle(8), 360)),
            ("filled square", reference.filled_square(60)),
            ("empty", np.zeros((30, 30), np.uint8))]


@pytest.mark.parametrize("n", [12, 60, 64, 90, 128, 360])
@pytest.mark.parametrize("density", [0.002, 0.05, 0.5, 0.98])
def test_occupied_box_kernel_matches_rolled_numpy_at_any_shift(n, density):
    """The bit-window kernel against roll + reshape + any on random images (seeded by n and the
    density), every divisor size (1 and n included, in shuffled order) and any whole-pixel shift."""
    from rockmass.fractal.boxcount import _count_raster_shifts

    rng = np.random.default_rng(n * 1000 + int(density * 1000))
    image = (rng.random((n, n)) < density).astype(np.uint8) * np.uint8(rng.choice([1, 255]))
    sizes = rng.permutation(divisors(n))
    off_r, off_c = _any_shifts(sizes, rng)
    counts = _count_raster_shifts(image, sizes, off_r, off_c)
    expected = [[naive_offset_boxes(image, int(s), int(r), int(c)) for r, c in zip(rr, cc)]
                for s, rr, cc in zip(sizes, off_r, off_c)]
    assert counts.tolist() == expected


@pytest.mark.parametrize("name, image", _reference_images(), ids=lambda v: v if isinstance(v, str) else "")
def test_occupied_box_kernel_matches_rolled_numpy_on_reference_fractals(name, image):
    from rockmass.fractal.boxcount import _count_raster_shifts

    rng = np.random.default_rng(31)
    sizes = divisors(image.shape[0])
    off_r, off_c = _any_shifts(sizes, rng)
    counts = _count_raster_shifts(image, sizes, off_r, off_c)
    expected = [[naive_offset_boxes(image, int(s), int(r), int(c)) for r, c in zip(rr, cc)]
                for s, rr, cc in zip(sizes, off_r, off_c)]
    assert counts.tolist() == expected


@pytest.mark.parametrize("shape", [(37, 53), (1, 64), (2, 65), (64, 128), (129, 63), (360, 360)])
@pytest.mark.parametrize("density", [0.05, 0.3, 0.7, 1.0])
def test_line_counts_match_numpy_oracle(shape, density):
    """Bit rows against whole-array numpy, across word boundaries (widths 53, 63-65, 128, 360)."""
    from rockmass.fractal.image import _line_counts

    rng = np.random.default_rng(int(density * 100) + shape[1])
    mask = (rng.random(shape) < density).astype(np.uint8)
    assert _line_counts(mask) == naive_line_statistics(mask)


@pytest.mark.parametrize("name, image", _reference_images(), ids=lambda v: v if isinstance(v, str) else "")
def test_line_counts_match_numpy_oracle_on_reference_fractals(name, image):
    from rockmass.fractal.image import _line_counts

    assert _line_counts(image) == naive_line_statistics(image)


def test_line_counts_without_numpy_bitwise_count(monkeypatch):
    """numpy < 2.0 has no ``bitwise_count``: the unpacked-bytes fallback gives the same counts."""
    from rockmass.fractal.image import _line_counts

    mask = (np.random.default_rng(41).random((70, 130)) < 0.4).astype(np.uint8)
    expected = naive_line_statistics(mask)
    monkeypatch.delattr(np, "bitwise_count", raising=False)
    assert _line_counts(mask) == expected


def test_grey_image_with_threshold_and_invert():
    img = np.full((120, 120), 200, dtype=np.uint8)
    img[60, :] = 10  # a dark horizontal line on a light background
    result = box_count(img, threshold=100, invert=True, n_offsets=1)
    assert result.dimension == pytest.approx(1.0, abs=1e-12)


def test_non_square_image_is_padded_and_says_so():
    img = np.zeros((100, 250), dtype=np.uint8)
    img[50, :] = 1  # a line across the whole width
    result = box_count(img, n_offsets=1)
    # 250 has only 8 divisors: padded to 270 = 2 * 3^3 * 5, the smallest 5-smooth side with >= 12
    assert result.grid == 270 and divisors(270).size >= 12
    assert any("padded" in n for n in result.notes)
    assert result.dimension == pytest.approx(1.0, abs=0.03)  # a line over 250 of the 270 px


def test_inputs_are_not_modified():
    seg = random_network(50, seed=14)
    img = rasterize_traces(seg, grid=90)
    seg_copy, img_copy = seg.copy(), img.copy()
    box_count(seg, method="vector")
    box_count(img, grid=90)
    assert np.array_equal(seg, seg_copy) and np.array_equal(img, img_copy)


def test_object_with_segments_method_is_accepted():
    seg = random_network(50, seed=15)

    class Traces:
        window_xy_m = None

        def segments(self):
            return seg

    assert box_count(Traces()).dimension == box_count(seg).dimension


def test_integer_segments_are_traces_and_uint8_quads_are_images():
    hough = np.array([[0, 0, 10, 10], [0, 10, 10, 0]], dtype=np.int32)  # cv2.HoughLinesP output
    assert box_count(hough, n_offsets=1).frame is not None
    tiny = np.zeros((8, 4), dtype=np.uint8)
    tiny[:, 1] = 1
    assert box_count(tiny, n_offsets=1, fit_range_px=(1, 8)).frame is None  # counted as an image
    floats = np.zeros((8, 4))
    floats[:, 1] = 1.0
    assert box_count(floats, kind="image", n_offsets=1, fit_range_px=(1, 8)).frame is None


def test_mask_with_a_hole_is_refused():
    import shapely

    polygon = shapely.Polygon([(0, 0), (10, 0), (10, 10), (0, 10)], [[(4, 4), (6, 4), (6, 6), (4, 6)]])
    with pytest.raises(ValueError, match="holes"):
        box_count(random_network(20, seed=20), mask=polygon)


def test_rasterize_with_a_window_clips_instead_of_bending():
    img = rasterize_traces(np.array([[0.0, 0.0, 20.0, 5.0]]), grid=10, window=(0, 0, 10, 10))
    rows = np.flatnonzero(img.any(axis=1))
    assert 10 - rows.min() <= 3  # leaves the window at v = 2.5: no pixel above row 3 from the bottom


def test_image_mask_of_the_wrong_shape_is_refused():
    img = np.eye(60, dtype=np.uint8)
    with pytest.raises(ValueError, match="shape"):
        box_count(img, mask=np.ones((30, 30), dtype=np.uint8))


def test_vector_count_by_sorting_box_ids_equals_the_mark_array():
    """Grids too large for a mark array (here: every grid) count distinct box ids instead."""
    from rockmass.fractal import _kernels

    seg = random_network(200, seed=21, extent=1.0)
    side = 1.0
    sizes = np.array([0.5, 0.1, 0.013, 0.002])
    offsets = np.array([[0.0, 0.0], [0.3, 0.7]])
    marked = np.zeros((4, 2), dtype=np.int64)
    sorted_ = np.zeros((4, 2), dtype=np.int64)
    totals = np.zeros((4, 2), dtype=np.int64)
    _kernels.count_crossed_boxes(seg, side, sizes, offsets, 1 << 24, marked, totals)
    _kernels.count_crossed_boxes(seg, side, sizes, offsets, 0, sorted_, totals)
    assert np.array_equal(marked, sorted_) and marked.min() > 0
