"""Box counting: run time and error side by side.

    python benchmarks/bench_fractal_boxcount.py

Table 1 — the speed targets of the fractal stage, with the error of each result:
count + fit of a 360 x 360 image at the default 8 grid offsets (target <= 1 ms) and vector counting
of 10^4 segments over 20 box sizes (target <= 100 ms); then the same image counted in plain numpy
and by porespy (when installed), with how much slower they are. Table 2 — run time against error over methods and grids (raster on 360,
720 and 1440, raster on the fractal's own base grid, exact vector counting) on reference fractals
with exact dimensions. Table 3 — the measurements behind the documented rules: the thick-line test
of binary images, the framing of a network's bounding square, the bias of face rescaling, and
whole-pixel against exact grid shifts. Rows also go to benchmarks/results/bench_fractal_boxcount.json.
"""

from __future__ import annotations

import math

import numpy as np

from _common import header, save, table, timed
from rockmass.fractal import box_count, rasterize_traces, reference


def random_network(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    c = rng.uniform(0, 100, size=(n, 2))
    a = rng.uniform(0, np.pi, size=n)
    half = rng.uniform(0.5, 6.0, size=n)[:, None]
    d = np.column_stack([np.cos(a), np.sin(a)]) * half
    return np.hstack([c - d, c + d])


def numpy_box_count(img: np.ndarray, n_offsets: int = 1) -> float:
    """D of a square 0/1 image in plain numpy: reshape + any per divisor size, grids shifted by
    np.roll (the same whole-pixel shifts as rockmass), np.polyfit over sizes up to a quarter."""
    from rockmass.fractal.boxcount import _raster_shifts, grid_offsets
    from rockmass.fractal.image import divisors

    n = img.shape[0]
    sizes = divisors(n)
    fit = sizes <= n / 4
    shifts = _raster_shifts(sizes, grid_offsets(n_offsets))
    slopes = []
    for b in range(n_offsets):
        counts = [np.roll(img, (int(shifts[a, b, 1]), int(shifts[a, b, 0])), axis=(0, 1))
                  .reshape(n // s, s, n // s, s).any(axis=(1, 3)).sum() for a, s in enumerate(sizes)]
        slopes.append(np.polyfit(-np.log(sizes[fit]), np.log(np.array(counts)[fit]), 1)[0])
    return float(slopes[0])


def comparison_rows(image: np.ndarray, ours: dict) -> list[dict]:
    """Plain numpy and porespy (when installed) on the random-network image, against rockmass's
    warm time at the same number of grid offsets (``ours``: offsets -> ms)."""
    rows = []
    for n_off in (1, 8):
        _, warm, d = timed(lambda: numpy_box_count(image, n_off), repeat=10)
        rows.append(dict(tool="plain numpy (reshape + any, np.roll, polyfit)",
                         setting=f"24 sizes, {n_off} offsets", warm_ms=1e3 * warm, D=d,
                         slower=1e3 * warm / ours[n_off]))
    try:
        from porespy.metrics import boxcount
    except ImportError:
        rows.append(dict(tool="porespy.metrics.boxcount", setting="not installed"))
        return rows
    _, warm, r = timed(lambda: boxcount(image), repeat=10)
    size, count = np.asarray(r.size, float), np.asarray(r.count, float)
    fit = size <= image.shape[0] / 4  # its counts fitted as ours are: sizes up to a quarter
    d = float(np.polyfit(-np.log(size[fit]), np.log(count[fit]), 1)[0])
    rows.append(dict(tool="porespy.metrics.boxcount", setting="default (sizes 10-360, 1 offset)",
                     warm_ms=1e3 * warm, D=d, slower=1e3 * warm / ours[1]))
    return rows


def speed_rows() -> list[dict]:
    rows = []
    image = rasterize_traces(random_network(400, seed=1), grid=360)
    exact_line = np.zeros((360, 360), np.uint8)
    exact_line[180, :] = 1
    for name, img, exact in (("random network 360² (400 traces)", image, None),
                             ("horizontal line 360²", exact_line, 1.0),
                             ("filled square 360²", reference.filled_square(360), 2.0)):
        for n_off in (1, 8):
            first, warm, r = timed(lambda: box_count(img, n_offsets=n_off), repeat=50)
            rows.append(dict(case=name, setting=f"raster, {n_off} offsets",
                             target="<= 1 ms" if n_off == 8 else "",
                             compile_s=first, warm_ms=1e3 * warm, D=r.dimension,
                             error=None if exact is None else abs(r.dimension - exact)))
    seg = random_network(10_000, seed=2)
    sizes = np.geomspace(1, 90, 20)
    for n_off in (1, 8):
        first, warm, r = timed(lambda: box_count(seg, method="vector", sizes_px=sizes,
                                                 fit_range_px=(1, 90), n_offsets=n_off), repeat=10)
        rows.append(dict(case="10^4 segments, 20 sizes", setting=f"vector, {n_off} offsets",
                         target="<= 100 ms" if n_off == 1 else "", compile_s=first,
                         warm_ms=1e3 * warm, D=r.dimension, error=None))
    koch = reference.polyline_segments(reference.koch_curve(7))
    first, warm, r = timed(lambda: box_count(koch, method="vector", n_offsets=1), repeat=10)
    rows.append(dict(case=f"Koch level 7 ({koch.shape[0]} segments)", setting="vector, 1 offset",
                     target="", compile_s=first, warm_ms=1e3 * warm, D=r.dimension,
                     error=abs(r.dimension - math.log(4) / math.log(3))))
    return rows


def accuracy_rows() -> list[dict]:
    rows = []
    pixel = [("sierpinski_triangle", reference.sierpinski_triangle(9)),
             ("sierpinski_carpet", reference.sierpinski_carpet(6)),
             ("cantor_dust", reference.cantor_dust(6)),
             ("vicsek", reference.vicsek(6))]
    for name, base in pixel:
        exact = reference.EXACT_DIMENSIONS[name]
        variants = [(f"base grid {base.shape[0]}", base)]
        variants += [(f"raster {g}", reference.embed(base, g)) for g in (360, 720, 1440)]
        for setting, img in variants:
            _, warm, r = timed(lambda: box_count(img, n_offsets=8, skeletonize="never"), repeat=5)
            rows.append(dict(fractal=name, method=setting, warm_ms=1e3 * warm, D=r.dimension,
                             error=r.dimension - exact, D_offset_mean=r.offset_mean,
                             offset_sd=r.offset_spread))
    koch = reference.polyline_segments(reference.koch_curve(8))
    exact = reference.EXACT_DIMENSIONS["koch_curve"]
    for setting, kwargs in [("raster 360", dict(grid=360)), ("raster 720", dict(grid=720)),
                            ("raster 1440", dict(grid=1440)),
                            ("vector (360 divisors)", dict(method="vector", grid=360)),
                            ("vector (1440 divisors)", dict(method="vector", grid=1440))]:
        _, warm, r = timed(lambda: box_count(koch, n_offsets=8, **kwargs), repeat=3)
        rows.append(dict(fractal="koch_curve (level 8)", method=setting, warm_ms=1e3 * warm,
                         D=r.dimension, error=r.dimension - exact, D_offset_mean=r.offset_mean,
                         offset_sd=r.offset_spread))
    return rows


def rule_rows() -> list[dict]:
    """The measurements behind the documented rules (fractal/image.py, framing.py, boxcount.py)."""
    import cv2

    from rockmass.fractal.image import THICK_FRACTION, _line_statistics

    rows = []
    for n in (100, 1500, 6000):  # thinning rule: 1-px networks stay below THICK_FRACTION
        seg = random_network(n, seed=1)
        img = rasterize_traces(seg, 360)
        rows.append(dict(rule="thick-line test", case=f"1-px network, {100 * img.mean():.0f}% fill",
                         value=_line_statistics(img)[0], note=f"thinned if > {THICK_FRACTION}"))
        thick = np.zeros((360, 360), np.uint8)
        for x0, y0, x1, y1 in (seg[: n // 15] * 3.6).round().astype(int):
            cv2.line(thick, (x0, y0), (x1, y1), 1, 3)
        rows.append(dict(rule="thick-line test", case=f"3-px lines, {100 * thick.mean():.0f}% fill",
                         value=_line_statistics(thick)[0], note=f"thinned if > {THICK_FRACTION}"))
    koch = reference.polyline_segments(reference.koch_curve(7))
    xs, ys = koch[:, 0::2], koch[:, 1::2]
    rows.append(dict(rule="framing", case="Koch 7, square anchored at lower-left",
                     value=box_count(koch, window=(0, 0, 1, 1), n_offsets=1).dimension,
                     note="exact 1.2619"))
    rows.append(dict(rule="framing", case="Koch 7, bounding square centred (default)",
                     value=box_count(koch, n_offsets=1).dimension, note="exact 1.2619"))
    bbox = np.array([[xs.min(), ys.min()], [xs.max(), ys.min()], [xs.max(), ys.max()],
                     [xs.min(), ys.max()]])
    rows.append(dict(rule="face rescaling", case="Koch 7, face = bounding rectangle",
                     value=box_count(koch, mask=bbox, n_offsets=1).dimension,
                     note="biased: the curve does not fill its rectangle"))
    rows.append(dict(rule="face rescaling", case="line across a 10 x 3 window",
                     value=box_count(np.array([[0.0, 1.5, 10.0, 1.5]]), window=(0, 0, 10, 3),
                                     n_offsets=1).dimension, note="exact 1"))
    line = rasterize_traces(reference.straight_line(45.0), 360)
    r = box_count(line, n_offsets=8)
    rows.append(dict(rule="whole-pixel shifts (image)", case="45° line drawn on 360², 8 grids",
                     value=r.offset_range[0], note=f"min D over grids; max {r.offset_range[1]:.3f}"))
    r = box_count(reference.straight_line(45.0), n_offsets=8)
    rows.append(dict(rule="exact shifts (traces)", case="45° line as a segment, 8 grids",
                     value=r.offset_range[0], note=f"min D over grids; max {r.offset_range[1]:.3f}"))
    return rows


def main() -> None:
    print(header("box counting: speed targets (median of warm calls; first call compiles; "
                 "8 offsets is the default)"))
    speed = speed_rows()
    print(table(speed, [("case", "s"), ("setting", "s"), ("target", "s"), ("compile_s", ".2f"),
                        ("warm_ms", ".3f"), ("D", ".4f"), ("error", ".1e")]))
    image = rasterize_traces(random_network(400, seed=1), grid=360)
    ours = {int(r["setting"].split()[1]): r["warm_ms"] for r in speed
            if r["case"].startswith("random network")}
    print("\nthe same random-network image (360²) counted by other tools; slower = their time over "
          "rockmass's at the same offsets")
    others = comparison_rows(image, ours)
    print(table(others, [("tool", "s"), ("setting", "s"), ("warm_ms", ".3f"), ("D", ".4f"),
                         ("slower", ".1f")]))
    print("\nbox counting: run time against error on reference fractals (fit 1 to grid/4, "
          "8 offsets; error = D - exact at zero offset; pixel fractals counted as drawn)")
    acc = accuracy_rows()
    print(table(acc, [("fractal", "s"), ("method", "s"), ("warm_ms", ".2f"), ("D", ".4f"),
                      ("error", "+.4f"), ("D_offset_mean", ".4f"), ("offset_sd", ".4f")]))
    print("\nthe measurements behind the documented rules")
    rules = rule_rows()
    print(table(rules, [("rule", "s"), ("case", "s"), ("value", ".4f"), ("note", "s")]))
    path = save("bench_fractal_boxcount", {"speed": speed, "others": others, "accuracy": acc,
                                           "rules": rules})
    print(f"\nrows written to {path}")


if __name__ == "__main__":
    main()
