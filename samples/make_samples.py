"""Regenerate the bundled samples (deterministic: the same files on every machine).

    python samples/make_samples.py

Writes, next to this script:

- ``face_traces.geojson`` — a synthetic trace map of a 12 m x 8 m tunnel face made by
  :func:`rockmass.imaging.synthetic_network` with its default three joint sets (mean angles 25°,
  115° and 160° counter-clockwise from +u, von Mises scatter, lognormal lengths, gentle wiggle, a
  share of younger traces abutting older ones), clipped to a horseshoe-shaped face outline, which
  is stored as the sampling window;
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
FACE_HEIGHT_M = 8.0
PX_PER_M = 100


def face_outline() -> np.ndarray:
    """Horseshoe face: vertical walls 5 m high, a semicircular crown of radius 6 m, ring (k, 2)."""
    crown = np.linspace(0.0, np.pi, 25)
    arch = np.column_stack([6.0 + 6.0 * np.cos(crown), 5.0 + 3.0 * np.sin(crown)])
    return np.vstack([[[0.0, 0.0], [12.0, 0.0]], arch[:-1], [[0.0, 5.0]]])


def main() -> None:
    import cv2

    from rockmass.dfn import TraceMap, write_traces
    from rockmass.imaging import synthetic_network
    from rockmass.imaging.synthetic import DEFAULT_SETS

    rng = np.random.default_rng(SEED)
    traces, set_ids = synthetic_network(face_outline(), DEFAULT_SETS, rng=rng)
    trace_map = TraceMap.from_polylines(
        traces, attributes={"id": np.arange(len(traces)), "set": set_ids},
        window=face_outline(), frame="face")
    write_traces(trace_map, HERE / "face_traces.geojson")

    h, w = int(FACE_HEIGHT_M * PX_PER_M), int(12.0 * PX_PER_M)
    image = np.zeros((h, w), dtype=np.uint8)
    for poly in traces:
        px = np.column_stack([poly[:, 0] * PX_PER_M, h - 1 - poly[:, 1] * PX_PER_M])
        cv2.polylines(image, [np.round(px).astype(np.int32)], False, 255, thickness=3)
    cv2.imwrite(str(HERE / "face_traces.png"), image)
    print(f"{len(traces)} traces in {len(DEFAULT_SETS)} sets -> {HERE / 'face_traces.geojson'}, "
          f"{HERE / 'face_traces.png'}")


if __name__ == "__main__":
    main()
