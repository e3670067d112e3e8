"""Regenerate the bundled samples (deterministic: the same files on every machine).

    python samples/make_samples.py

Writes, next to this script:

- ``face_traces.geojson`` — a synthetic trace map of a 12 m x 8 m tunnel face: three joint sets
  (mean angles 25°, 115° and 160° counter-clockwise from +u, von Mises scatter), lognormal trace
  lengths, gentle wiggle, a share of set-2 traces abutting older traces (T-terminations), clipped to
  a horseshoe-shaped face outline, which is stored as the sampling window;
- ``face_traces.png`` — the same network drawn with 3-pixel lines at 100 px/m (1200 x 800 px),
  white on black, the way a digitised or segmented face arrives; ``rockmass boxcount`` thins it to
  1-pixel lines before counting and says so.

The samples are inputs a new user runs first; the test suite reads them but asserts nothing that the
script merely produced (tests compare the CLI against the API on them).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20261121
FACE_WIDTH_M, FACE_HEIGHT_M = 12.0, 8.0
# (mean angle deg, von Mises kappa on 2θ, mean length m, lognormal sigma, count, abut fraction)
SETS = [(25.0, 40.0, 2.6, 0.5, 70, 0.0),
        (115.0, 25.0, 1.8, 0.45, 90, 0.5),
        (160.0, 60.0, 3.2, 0.4, 35, 0.2)]
PX_PER_M = 100


def face_outline() -> np.ndarray:
    """Horseshoe face: vertical walls 5 m high, a semicircular crown of radius 6 m, ring (k, 2)."""
    crown = np.linspace(0.0, np.pi, 25)
    arch = np.column_stack([6.0 + 6.0 * np.cos(crown), 5.0 + 3.0 * np.sin(crown)])
    return np.vstack([[[0.0, 0.0], [12.0, 0.0]], arch[:-1], [[0.0, 5.0]]])


def _wiggly(p0, p1, rng, n_inner=3, amplitude=0.04):
    """A polyline from p0 to p1 with small perpendicular wiggle at evenly spaced inner vertices."""
    t = np.linspace(0.0, 1.0, n_inner + 2)[:, None]
    pts = p0 + t * (p1 - p0)
    d = p1 - p0
    normal = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-12)
    offsets = rng.normal(0.0, amplitude * np.hypot(*d) / 4, size=(n_inner + 2, 1))
    offsets[[0, -1]] = 0.0
    return pts + offsets * normal


def make_network(rng: np.random.Generator):
    """Lines of every set, older sets first, with T-terminations against what exists already."""
    import shapely

    face = shapely.Polygon(face_outline())
    existing = []
    traces, set_ids = [], []
    for set_id, (angle, kappa, mean_len, sigma, count, abut) in enumerate(SETS, start=1):
        theta = np.deg2rad(angle) + 0.5 * rng.vonmises(0.0, kappa, size=count)
        lengths = rng.lognormal(np.log(mean_len) - 0.5 * sigma**2, sigma, size=count)
        centres = rng.uniform([-1.0, -1.0], [FACE_WIDTH_M + 1, FACE_HEIGHT_M + 1], size=(count, 2))
        abutting = rng.random(count) < abut
        for c, th, length, stops in zip(centres, theta, lengths, abutting):
            d = 0.5 * length * np.array([np.cos(th), np.sin(th)])
            line = shapely.LineString(_wiggly(c - d, c + d, rng))
            if stops and existing:
                hits = line.intersection(shapely.union_all(existing))
                if not hits.is_empty:
                    # cut at the crossing nearest the start: the trace abuts an older one
                    first = min(line.project(p) for p in shapely.get_parts(hits))
                    if first > 0.05:
                        line = shapely.ops.substring(line, 0.0, first)
            clipped = line.intersection(face)
            for part in shapely.get_parts(clipped):
                if part.geom_type == "LineString" and part.length > 0.05:
                    traces.append(np.asarray(part.coords))
                    set_ids.append(set_id)
                    existing.append(part)
    return traces, np.array(set_ids)


def main() -> None:
    import cv2
    import shapely.ops  # noqa: F401  (substring)

    from rockmass.dfn import TraceMap, write_traces

    rng = np.random.default_rng(SEED)
    traces, set_ids = make_network(rng)
    trace_map = TraceMap.from_polylines(
        traces, attributes={"id": np.arange(len(traces)), "set": set_ids},
        window=face_outline(), frame="face")
    write_traces(trace_map, HERE / "face_traces.geojson")

    h, w = int(FACE_HEIGHT_M * PX_PER_M), int(FACE_WIDTH_M * PX_PER_M)
    image = np.zeros((h, w), dtype=np.uint8)
    for poly in traces:
        px = np.column_stack([poly[:, 0] * PX_PER_M, h - 1 - poly[:, 1] * PX_PER_M])
        cv2.polylines(image, [np.round(px).astype(np.int32)], False, 255, thickness=3)
    cv2.imwrite(str(HERE / "face_traces.png"), image)
    print(f"{len(traces)} traces in {len(SETS)} sets -> {HERE / 'face_traces.geojson'}, "
          f"{HERE / 'face_traces.png'}")


if __name__ == "__main__":
    main()
