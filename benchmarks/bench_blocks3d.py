"""3D blocks by plane cutting: run time against geometric error and block counts.

Table 1 — three orthogonal Poisson sets (P10 = λ on each axis) in a unit cube: the count of blocks is
exactly Π(1 + N_i) for the N_i planes drawn on each axis (error column: count − that product, must be
0), and Σ volume = 1 (error column: relative volume balance). Sizes grow with λ.

Table 2 — DFN realizations with the seed-001 orientations (Fisher κ = 20; power-law radii) in a box of
side L around two crossing horseshoe tunnels: disks, convex pieces, in-situ blocks, keyblocks by mode,
time to cut, to analyse keyblocks and to compute shapes, and the volume balance (Σ pieces = box).

Table 3 — scaling to 10⁵ blocks (issue 21): orthogonal Poisson sets (λ per axis chosen for ~10³, 10⁴,
10⁵ blocks; exact count Π(1 + N_i)), three oblique persistent sets at fine spacing in a unit cube, and
a dense seed-001-like DFN without tunnels. Each case runs in a fresh process (after a small warm-up
cut, so numba compilation is not timed): seconds per phase of ``cut_box`` (cut: the numba kernel plus
building the ``Polyhedron`` objects; moments; links: shared faces and their real areas; grouping),
blocks per second, peak resident memory above the warmed-up process and the error columns. The
cold compile time of the kernels (empty ``NUMBA_CACHE_DIR``) is reported apart. ``--reference`` runs
the same table with the numpy cutting path (``split`` per piece).

    python benchmarks/bench_blocks3d.py [--quick] [--reference]
"""

from __future__ import annotations

import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import header, save, table  # noqa: E402


def poisson_planes(lam: float, seed: int):
    """Three orthogonal Poisson sets of intensity λ in the unit cube, and their plane counts."""
    import numpy as np

    from rockmass.blockgen.blocks3d import Planes

    rng = np.random.default_rng(seed)
    planes, counts = [], []
    for i, axis in enumerate(np.eye(3)):
        offsets = np.sort(rng.uniform(0.0, 1.0, rng.poisson(lam)))
        m = len(offsets)
        counts.append(m)
        planes.append(Planes(np.tile(axis, (m, 1)), offsets, np.full(m, i), np.zeros((m, 3)), np.full(m, np.inf)))
    return planes, counts


def poisson_case(lam: float, seed: int) -> dict:
    from rockmass.blockgen.blocks3d import cut_box

    planes, counts = poisson_planes(lam, seed)
    t0 = time.perf_counter()
    blocks = cut_box([[0, 0, 0], [1, 1, 1]], *planes)
    seconds = time.perf_counter() - t0
    expected = math.prod(1 + n for n in counts)
    return {"lambda": lam, "blocks": blocks.n_blocks, "count_error": blocks.n_blocks - expected,
            "volume_error": abs(blocks.volume_m3.sum() - 1.0), "cut_s": seconds,
            "blocks_per_s": blocks.n_blocks / seconds}


def seed001_network(side: float, p32: float, realization: int = 0):
    """The seed-001 orientations (Fisher κ = 20) with power-law radii at total P32 in a cube."""
    import numpy as np

    from rockmass.dfn import FisherOrientation, FractureSetSpec, IntensityP32, generate
    from rockmass.dfn.sizes import PowerLawSize

    sets = [FractureSetSpec(FisherOrientation(d, dd, 20.0), PowerLawSize(r, 40.0, 2.5), IntensityP32(p32 / 3))
            for d, dd, r in ((50, 270, 3.53), (80, 10, 2.51), (70, 150, 2.84))]
    box = np.array([[0.0, 0.0, 0.0], [side, side, side]])
    return box, generate(sets, box, seed=1, realization=realization)


def dfn_case(side: float, p32: float) -> dict:
    from rockmass.blockgen.block_shapes import block_shapes
    from rockmass.blockgen.blocks3d import cut_box, disk_planes
    from rockmass.blockgen.keyblocks import keyblocks
    from rockmass.blockgen.openings3d import Tunnel, horseshoe_section

    box, network = seed001_network(side, p32)
    tunnels = (Tunnel(horseshoe_section(6.0, 3.0), centre_m=(side / 2, 0, side / 2 - 3), trend_deg=0.0),
               Tunnel(horseshoe_section(6.0, 3.0), centre_m=(0, side / 2, side / 2 - 3), trend_deg=90.0))
    t0 = time.perf_counter()
    blocks = cut_box(box, disk_planes(network), tunnels=tunnels)
    t1 = time.perf_counter()
    results = keyblocks(blocks, {i: (30.0, 0.0) for i in range(len(network.radius_m))})
    t2 = time.perf_counter()
    block_shapes(blocks)
    t3 = time.perf_counter()
    modes = Counter(r.mode for r in results)
    return {"side_m": side, "p32": p32, "disks": len(network.radius_m), "pieces": len(blocks.pieces),
            "blocks": blocks.n_blocks, "fall": modes["fall"], "slide": modes["slide"] + modes["slide2"],
            "cut_s": t1 - t0, "keyblocks_s": t2 - t1, "shapes_s": t3 - t2,
            "volume_error": abs(blocks.volume_m3.sum() / side ** 3 - 1.0)}


def p32_case(p32: float, realizations: int, side: float = 15.0) -> dict:
    """In-situ block size against intensity: the seed-001 sets in a cube without openings, over
    ``realizations`` realizations; median block volume and lognormal log-mean (mean ± sd)."""
    import numpy as np

    from rockmass.blockgen.block_shapes import volume_distribution
    from rockmass.blockgen.blocks3d import cut_box, disk_planes

    medians, log_means, counts, seconds = [], [], [], 0.0
    for r in range(realizations):
        box, network = seed001_network(side, p32, r)
        t0 = time.perf_counter()
        blocks = cut_box(box, disk_planes(network))
        seconds += time.perf_counter() - t0
        dist = volume_distribution(blocks.block_volumes_m3())
        medians.append(dist.quantiles["0.5"])
        log_means.append(dist.log_mean)
        counts.append(blocks.n_blocks)
    return {"p32": p32, "realizations": realizations, "blocks_per_m3": float(np.mean(counts)) / side ** 3,
            "median_m3": float(np.mean(medians)), "median_sd_m3": float(np.std(medians, ddof=1)),
            "log_mean": float(np.mean(log_means)), "log_mean_sd": float(np.std(log_means, ddof=1)),
            "cut_s_per_realization": seconds / realizations}


#: Table 3 cases: (kind, parameter, nominal blocks). orthogonal: λ per axis; oblique: planes per unit
#: length of each set; dfn: P32 (m²/m³) in a 20 m cube.
SCALE_CASES = (("orthogonal", 9.0, "1e3"), ("orthogonal", 21.0, "1e4"), ("orthogonal", 45.0, "1e5"),
               ("oblique", 17.0, "1e3"), ("oblique", 40.0, "1e4"), ("oblique", 92.0, "1e5"),
               ("dfn", 2.0, "1e3"), ("dfn", 6.0, "1e4"), ("dfn", 7.5, "1e5"))


def scale_planes(kind: str, parameter: float):
    """(box, planes, exact block count or None) of one Table 3 case."""
    import numpy as np

    from rockmass.blockgen.blocks3d import disk_planes, persistent_set_planes

    if kind == "orthogonal":
        planes, counts = poisson_planes(parameter, seed=1)
        return np.array([[0.0] * 3, [1.0] * 3]), planes, math.prod(1 + n for n in counts)
    if kind == "oblique":
        box = np.array([[0.0] * 3, [1.0] * 3])
        rng = np.random.default_rng(3)     # fixed seed: three set normals and origins
        normals = rng.normal(size=(3, 3))
        return box, [persistent_set_planes(box, n, 1.0 / parameter, origin_m=rng.uniform(0, 1, 3), label=i)
                     for i, n in enumerate(normals)], None
    box, network = seed001_network(20.0, parameter)
    return box, [disk_planes(network)], None


def scale_case(kind: str, parameter: float, reference: bool) -> dict:
    """One Table 3 row, measured in this (fresh) process."""
    import numpy as np

    from rockmass.blockgen import blocks3d

    blocks3d._USE_KERNELS = not reference
    blocks3d.cut_box([[0, 0, 0], [1, 1, 1]], *scale_planes("oblique", 3.0)[1])     # warm-up (compiles)
    box, planes, exact = scale_planes(kind, parameter)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    blocks = blocks3d.cut_box(box, *planes)
    seconds = time.perf_counter() - t0
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"case": kind, "param": parameter, "planes": sum(len(p) for p in planes), "pieces": len(blocks.pieces),
            "blocks": blocks.n_blocks, **{f"{k}_s": v for k, v in blocks.timings_s.items()}, "total_s": seconds,
            "blocks_per_s": blocks.n_blocks / seconds, "peak_mb": (rss1 - rss0) / 1024,
            "count_error": None if exact is None else blocks.n_blocks - exact,
            "volume_error": abs(blocks.volume_m3.sum() / np.prod(box[1] - box[0]) - 1.0)}


def compile_case() -> dict:
    """First and second small cut in this process (run with an empty NUMBA_CACHE_DIR)."""
    from rockmass.blockgen.blocks3d import cut_box

    box, planes, _ = scale_planes("oblique", 3.0)
    t0 = time.perf_counter()
    cut_box(box, *planes)
    t1 = time.perf_counter()
    cut_box(box, *planes)
    t2 = time.perf_counter()
    return {"first_s": t1 - t0, "second_s": t2 - t1, "compile_s": (t1 - t0) - (t2 - t1)}


def in_fresh_process(args: list[str], env: dict | None = None) -> dict:
    out = subprocess.run([sys.executable, __file__, *args], capture_output=True, text=True, check=True,
                         env={**os.environ, **(env or {})})
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    if "--case" in sys.argv:
        kind, parameter = sys.argv[sys.argv.index("--case") + 1:sys.argv.index("--case") + 3]
        print(json.dumps(compile_case() if kind == "compile" else
                         scale_case(kind, float(parameter), "--reference" in sys.argv)))
        return
    quick = "--quick" in sys.argv
    reference = ["--reference"] if "--reference" in sys.argv else []
    print(header("3D blocks: plane cutting, keyblocks and shapes"))
    rows = [poisson_case(lam, seed) for lam in ((3.0, 6.0) if quick else (3.0, 6.0, 10.0, 16.0))
            for seed in (1, 2)]
    print("\nTable 1 - orthogonal Poisson sets in a unit cube (count error must be 0)")
    print(table(rows, [("lambda", ".0f"), ("blocks", "d"), ("count_error", "d"), ("volume_error", ".1e"),
                       ("cut_s", ".3f"), ("blocks_per_s", ".0f")]))
    dfn_rows = [dfn_case(side, p32) for side, p32 in (((20.0, 0.5),) if quick else
                                                     ((20.0, 0.5), (20.0, 1.0), (30.0, 1.0)))]
    print("\nTable 2 - seed-001 DFN around two crossing horseshoe tunnels (6 m wide)")
    print(table(dfn_rows, [("side_m", ".0f"), ("p32", ".1f"), ("disks", "d"), ("pieces", "d"),
                           ("blocks", "d"), ("fall", "d"), ("slide", "d"), ("cut_s", ".2f"),
                           ("keyblocks_s", ".2f"), ("shapes_s", ".2f"), ("volume_error", ".1e")]))
    sweep = [p32_case(p32, 3 if quick else 5) for p32 in ((0.5, 1.0, 2.0) if quick else (0.5, 1.0, 2.0, 4.0))]
    print("\nTable 2b - in-situ block size against P32 (seed-001 sets, 15 m cube, mean ± sd over realizations)")
    print(table(sweep, [("p32", ".1f"), ("realizations", "d"), ("blocks_per_m3", ".3f"), ("median_m3", ".3g"),
                        ("median_sd_m3", ".2g"), ("log_mean", ".2f"), ("log_mean_sd", ".2f"),
                        ("cut_s_per_realization", ".2f")]))
    scale_rows = [in_fresh_process(["--case", kind, str(parameter), *reference])
                  for kind, parameter, nominal in SCALE_CASES if not (quick and nominal == "1e5")]
    print("\nTable 3 - scaling (fresh process per row; peak_mb = peak RSS growth during cut_box)")
    print(table(scale_rows, [("case", "s"), ("param", "g"), ("planes", "d"), ("pieces", "d"), ("blocks", "d"),
                             ("cut_s", ".2f"), ("moments_s", ".3f"), ("links_s", ".2f"), ("grouping_s", ".3f"),
                             ("total_s", ".2f"), ("blocks_per_s", ".0f"), ("peak_mb", ".0f"),
                             ("count_error", "d"), ("volume_error", ".1e")]))
    with tempfile.TemporaryDirectory() as cache:
        cold = in_fresh_process(["--case", "compile", "0"], env={"NUMBA_CACHE_DIR": cache})
    print(f"\ncold numba compile (empty cache): first small cut {cold['first_s']:.2f} s, "
          f"second {cold['second_s']:.3f} s, compile ~{cold['compile_s']:.2f} s")
    save("bench_blocks3d", {"poisson": rows, "dfn": dfn_rows, "p32_sweep": sweep, "scale": scale_rows,
                            "cold_compile": cold,
                            "reference_path": bool(reference)})


if __name__ == "__main__":
    main()
