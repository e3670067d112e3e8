"""3D blocks by plane cutting: run time against geometric error and block counts.

Table 1 — three orthogonal Poisson sets (P10 = λ on each axis) in a unit cube: the count of blocks is
exactly Π(1 + N_i) for the N_i planes drawn on each axis (error column: count − that product, must be
0), and Σ volume = 1 (error column: relative volume balance). Sizes grow with λ.

Table 2 — DFN realizations with the seed-001 orientations (Fisher κ = 20; power-law radii) in a box of
side L around two crossing horseshoe tunnels: disks, convex pieces, in-situ blocks, keyblocks by mode,
time to cut, to analyse keyblocks and to compute shapes, and the volume balance (Σ pieces = box).

    python benchmarks/bench_blocks3d.py [--quick]
"""

from __future__ import annotations

import math
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import header, save, table  # noqa: E402


def poisson_case(lam: float, seed: int) -> dict:
    import numpy as np

    from rockmass.blockgen.blocks3d import Planes, cut_box

    rng = np.random.default_rng(seed)
    planes, counts = [], []
    for i, axis in enumerate(np.eye(3)):
        offsets = np.sort(rng.uniform(0.0, 1.0, rng.poisson(lam)))
        m = len(offsets)
        counts.append(m)
        planes.append(Planes(np.tile(axis, (m, 1)), offsets, np.full(m, i), np.zeros((m, 3)), np.full(m, np.inf)))
    t0 = time.perf_counter()
    blocks = cut_box([[0, 0, 0], [1, 1, 1]], *planes)
    seconds = time.perf_counter() - t0
    expected = math.prod(1 + n for n in counts)
    return {"lambda": lam, "blocks": blocks.n_blocks, "count_error": blocks.n_blocks - expected,
            "volume_error": abs(blocks.volume_m3.sum() - 1.0), "cut_s": seconds,
            "blocks_per_s": blocks.n_blocks / seconds}


def dfn_case(side: float, p32: float) -> dict:
    import numpy as np

    from rockmass.blockgen.block_shapes import block_shapes
    from rockmass.blockgen.blocks3d import cut_box, disk_planes
    from rockmass.blockgen.keyblocks import keyblocks
    from rockmass.blockgen.openings3d import Tunnel, horseshoe_section
    from rockmass.dfn import FisherOrientation, FractureSetSpec, IntensityP32, generate
    from rockmass.dfn.sizes import PowerLawSize

    sets = [FractureSetSpec(FisherOrientation(d, dd, 20.0), PowerLawSize(r, 40.0, 2.5), IntensityP32(p32 / 3))
            for d, dd, r in ((50, 270, 3.53), (80, 10, 2.51), (70, 150, 2.84))]
    box = np.array([[0.0, 0.0, 0.0], [side, side, side]])
    network = generate(sets, box, seed=1)
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


def main() -> None:
    quick = "--quick" in sys.argv
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
    save("bench_blocks3d", {"poisson": rows, "dfn": dfn_rows})


if __name__ == "__main__":
    main()
