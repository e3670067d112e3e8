"""DFN generation and virtual sampling: run time against error.

    python benchmarks/bench_dfn_generate.py

1. Generation of about 10^4, 10^5 and 10^6 disks (one Fisher set, κ = 20, radius 0.5 m, P32 = 2 m²/m³
   in a cube sized for the count): first call (numba compile or cache load) and warm time, achieved
   clipped P32 against the target (relative error; the fill rule overshoots by less than one disk).
2. Clipped-area accuracy: P32 of a 10^5-disk power-law network (r 0.3-6 m, many disks cut by the box)
   with the clipping polygon at 16 / 64 / 256 vertices, against 4096 vertices.
3. Plane sampling of the 10^6-disk network: time, number of traces, P21 against P32 / C23.
4. Direct section vs volume-then-cut on a vertical plane through a box 600 m deep (constant radius
   0.5 m): time per realization, P21 and mean trace length over 20 realizations each, against
   P32 / C23 (with the relative σ of the estimate, sqrt((1 + cv²)/N)) and each other (the
   window-censored mean length).

Seeds are fixed (1, 2, 3, 100+); rows also go to benchmarks/results/bench_dfn_generate.json.
"""

from __future__ import annotations

import numpy as np

from _common import header, save, table, timed
from rockmass.dfn import ConstantSize, PowerLawSize, c23
from rockmass.dfn.generation import FisherOrientation, FractureSetSpec, IntensityP32, generate
from rockmass.dfn.sampling import sample_plane
from rockmass.dfn.section import generate_section

P32 = 2.0
SPEC = FractureSetSpec(FisherOrientation(60.0, 120.0, 20.0), ConstantSize(0.5), IntensityP32(P32))


def cube_for(n: float) -> list[float]:
    side = (n / SPEC.p30) ** (1.0 / 3.0)
    return [0.0, 0.0, 0.0, side, side, side]


def bench_generation():
    rows, networks = [], {}
    for n in (10_000, 100_000, 1_000_000):
        box = cube_for(n)
        first, warm, net = timed(lambda: generate([SPEC], box, seed=1), repeat=3 if n == 1_000_000 else 5)
        networks[n] = net
        achieved = net.p32()
        rows.append({"disks": net.n_fractures, "side_m": box[3], "first_s": first, "warm_s": warm,
                     "target_p32": P32, "achieved_p32": achieved, "rel_error": (achieved - P32) / P32})
    return rows, networks


def bench_clipping():
    spec = FractureSetSpec(FisherOrientation(60.0, 120.0, 20.0), PowerLawSize(0.3, 6.0, 2.0), IntensityP32(P32))
    side = (100_000 / spec.p30) ** (1 / 3)
    net = generate([spec], [0, 0, 0, side, side, side], seed=2)
    reference = net.clipped_area_m2(n_vertices=4096).sum() / net.volume_m3
    rows = []
    for m in (16, 64, 256):
        first, warm, area = timed(lambda: net.clipped_area_m2(n_vertices=m), repeat=5)
        p32 = area.sum() / net.volume_m3
        rows.append({"vertices": m, "disks": net.n_fractures, "warm_s": warm, "p32": p32,
                     "rel_error": abs(p32 - reference) / reference})
    return rows


def bench_plane(net):
    side = net.domain_m[1, 0]
    h = side / 4  # a square of side side/2 through the centre stays inside the cube for any normal
    window = [(-h, -h), (h, -h), (h, h), (-h, h)]
    rows = []
    for normal in ([1.0, 0.0, 0.0], [1.0, 1.0, 0.5]):
        first, warm, tm = timed(lambda: sample_plane(net, [side / 2] * 3, normal, window), repeat=5)
        expected = P32 / float(c23(normal, SPEC.orientation.mean_pole, 20.0))
        p21 = tm.total_length_m() / (2 * h) ** 2
        lengths = tm.lengths_m()
        rows.append({"disks": net.n_fractures, "normal": str(normal), "warm_s": warm, "traces": tm.n_traces,
                     "p21": p21, "expected_p21": expected, "rel_error": (p21 - expected) / expected,
                     "rel_sigma": np.sqrt((1 + (lengths.std() / lengths.mean()) ** 2) / lengths.size)})
    return rows


def bench_section(k: int = 20):
    box = [0.0, 0.0, 0.0, 20.0, 600.0, 20.0]           # 600 m deep along y
    point, normal = [10.0, 300.0, 10.0], [0.0, 1.0, 0.0]
    window = [(-8.0, -8.0), (8.0, -8.0), (8.0, 8.0), (-8.0, 8.0)]
    area = 256.0

    def direct(i):
        return generate_section([SPEC], point, normal, window, seed=100, realization=i)

    def volume(i):
        return sample_plane(generate([SPEC], box, seed=101, realization=i), point, normal, window)

    expected = P32 / float(c23(normal, SPEC.orientation.mean_pole, 20.0))
    rows = []
    for name, fn in (("direct section", direct), ("volume then cut", volume)):
        _, warm, _ = timed(lambda: fn(0), repeat=3)
        maps = [fn(i) for i in range(k)]
        lengths = np.concatenate([t.lengths_m() for t in maps])
        p21 = lengths.sum() / (area * k)
        rel_sigma = np.sqrt((1 + (lengths.std() / lengths.mean()) ** 2) / lengths.size)
        rows.append({"method": name, "warm_s": warm, "traces": lengths.size, "p21": p21, "expected_p21": expected,
                     "p21_rel_error": (p21 - expected) / expected, "p21_rel_sigma": rel_sigma, "mean_length_m": lengths.mean(),
                     "mean_length_se_m": lengths.std() / np.sqrt(lengths.size)})
    rows[0]["speedup"] = rows[1]["warm_s"] / rows[0]["warm_s"]
    return rows


def main() -> None:
    print(header("DFN generation and virtual sampling: run time and error"))
    gen_rows, networks = bench_generation()
    print("\n1. generation to a clipped P32 target (Fisher κ=20, r=0.5 m, P32=2)")
    print(table(gen_rows, [("disks", "d"), ("side_m", ".1f"), ("first_s", ".3f"), ("warm_s", ".3f"),
                           ("target_p32", ".3f"), ("achieved_p32", ".6f"), ("rel_error", ".2e")]))
    clip_rows = bench_clipping()
    print("\n2. clipped area: polygon vertices vs error of P32 (reference 4096 vertices)")
    print(table(clip_rows, [("vertices", "d"), ("disks", "d"), ("warm_s", ".3f"), ("p32", ".6f"),
                            ("rel_error", ".2e")]))
    plane_rows = bench_plane(networks[1_000_000])
    print("\n3. plane sampling of the 10^6-disk network (square window through the centre, side = cube side / 2)")
    print(table(plane_rows, [("disks", "d"), ("normal", "s"), ("warm_s", ".3f"), ("traces", "d"),
                             ("p21", ".4f"), ("expected_p21", ".4f"), ("rel_error", ".2e"),
                             ("rel_sigma", ".2e")]))
    section_rows = bench_section()
    print("\n4. direct section vs volume then cut (box 20 x 600 x 20 m, window 16 x 16 m, 20 realizations)")
    print(table(section_rows, [("method", "s"), ("warm_s", ".4f"), ("speedup", ".0f"), ("traces", "d"),
                               ("p21", ".4f"), ("expected_p21", ".4f"), ("p21_rel_error", ".2e"),
                               ("p21_rel_sigma", ".2e"), ("mean_length_m", ".4f"), ("mean_length_se_m", ".4f")]))
    path = save("bench_dfn_generate", {"generation": gen_rows, "clipping": clip_rows, "plane": plane_rows,
                                       "section": section_rows})
    print(f"\nrows written to {path}")


if __name__ == "__main__":
    main()
