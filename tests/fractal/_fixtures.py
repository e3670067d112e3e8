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


def shapely_crossed_boxes(segments: np.ndarray, x0: float, y0: float, box: float, n_boxes: int,
                          shift=(0.0, 0.0), fold: bool = False) -> int:
    """Boxes whose interior a segment crosses with positive length, by shapely (independent oracle).

    The grid has ``n_boxes`` x ``n_boxes`` boxes of side ``box`` with corners at
    ``(x0 - shift[0] + i * box, y0 - shift[1] + j * box)``; with ``fold`` the grid is cyclic on the
    square of side ``(n_boxes - 1) * box`` (the last row and column are the first ones again).
    Only for small grids: every box is intersected with every segment.
    """
    import shapely

    union = shapely.union_all(shapely.linestrings(segments.reshape(-1, 2, 2)))
    hit = set()
    for i in range(n_boxes):
        for j in range(n_boxes):
            bx, by = x0 - shift[0] + i * box, y0 - shift[1] + j * box
            cell = shapely.box(bx, by, bx + box, by + box)
            inner = shapely.intersection(union, cell)
            # a piece lying on the cell's boundary is not inside its interior
            if shapely.length(shapely.difference(inner, cell.exterior)) > 1e-9 * box:
                m = n_boxes - 1 if fold else n_boxes
                hit.add((i % m, j % m) if fold else (i, j))
    return len(hit)


def shapely_face_boxes(ring: np.ndarray, x0: float, y0: float, box: float, n_boxes: int) -> int:
    """Boxes of the grid whose interior overlaps the polygon with positive area (shapely)."""
    import shapely

    polygon = shapely.Polygon(ring)
    return sum(shapely.box(x0 + i * box, y0 + j * box, x0 + (i + 1) * box, y0 + (j + 1) * box)
               .intersection(polygon).area > 1e-12 * box * box
               for i in range(n_boxes) for j in range(n_boxes))


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
