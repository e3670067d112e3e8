"""Small inputs with answers that can be worked out by hand, and independent counting oracles."""

import numpy as np


def random_network(n: int, seed: int, extent: float = 10.0) -> np.ndarray:
    """``n`` random segments ``(n, 4)`` in a square of side ``extent`` (seeded)."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0.0, extent, size=(n, 2))
    angles = rng.uniform(0.0, np.pi, size=n)
    half = rng.uniform(0.02, 0.2, size=n)[:, None] * extent
    d = np.column_stack([np.cos(angles), np.sin(angles)]) * half
    return np.hstack([centres - d, centres + d])


def naive_occupied_boxes(mask: np.ndarray, size: int) -> int:
    """Occupied boxes of a square mask at a divisor ``size`` by reshape + any (numpy only)."""
    n = mask.shape[0]
    m = n // size
    return int(mask.reshape(m, size, m, size).any(axis=(1, 3)).sum())


def naive_offset_boxes(mask: np.ndarray, size: int, off_r: int, off_c: int) -> int:
    """Occupied boxes of the box grid shifted cyclically by (off_r, off_c) pixels: roll, then reshape."""
    return naive_occupied_boxes(np.roll(mask, (off_r, off_c), axis=(0, 1)), size)


def shapely_crossed_boxes(segments: np.ndarray, x0: float, y0: float, box: float, n_boxes: int) -> int:
    """Boxes of an ``n_boxes`` x ``n_boxes`` grid whose interior a segment crosses with positive length.

    Independent of the traversal kernel: shapely intersects every box with every segment. Only for
    small grids.
    """
    import shapely

    lines = shapely.linestrings(segments.reshape(-1, 2, 2))
    union = shapely.union_all(lines)
    count = 0
    for i in range(n_boxes):
        for j in range(n_boxes):
            cell = shapely.box(x0 + i * box, y0 + j * box, x0 + (i + 1) * box, y0 + (j + 1) * box)
            inner = shapely.intersection(union, cell)
            # a piece lying on the cell's boundary is not inside its interior
            if shapely.length(shapely.difference(inner, cell.exterior)) > 1e-9 * box:
                count += 1
    return count


def naive_line_statistics(mask: np.ndarray) -> tuple[int, int, int]:
    """(trace pixels, pixels in a full 2x2 block, interior pixels) with whole-array numpy logic."""
    m = mask.astype(bool)
    full = m[:-1, :-1] & m[1:, :-1] & m[:-1, 1:] & m[1:, 1:]
    in_full = np.zeros_like(m)
    in_full[:-1, :-1] |= full
    in_full[1:, :-1] |= full
    in_full[:-1, 1:] |= full
    in_full[1:, 1:] |= full
    p = np.pad(m, 1)
    interior = p[1:-1, 1:-1] & p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:]
    return int(m.sum()), int(in_full.sum()), int(interior.sum())
