"""DFN closed loop: generate with known sets, sample like the field, re-fit, compare — time and error.

    python benchmarks/bench_dfn_validate.py

Three Fisher sets (the orientations of Kiran & Juneja 2022, κ = 20), power-law radii r 1-20 m with α = 2.5,
P32 = 1 m²/m³ each, in cubes of side 20, 40 and 80 m. Field geometry: three orthogonal scanlines
through the centre (2 m from the faces of the cube) and three orthogonal square faces through the
centre with windows of 0.75 side. Each size is run for two seeds. Per run: generation, virtual
sampling and fit times (fit = pole clustering, censored-length likelihood for α and r_min, NNLS P32),
then the errors against the truth: the largest mean-pole angle over sets, the largest |κ̂ − κ|/κ, the
largest |P̂32 − P32|/P32 (P32 achieved by the realization), the largest |α̂ − α|, and how many of the
15 checks (:func:`rockmass.dfn.validation.compare_fit`: 3σ, pole 1.52 α95) pass.

Seeds 1 and 2; rows also go to benchmarks/results/bench_dfn_validate.json.
"""

from __future__ import annotations

import time

import numpy as np

from _common import header, save, table
from rockmass.dfn.field_fit import fit_field
from rockmass.dfn.generation import FisherOrientation, FractureSetSpec, IntensityP32, generate
from rockmass.dfn.sizes import PowerLawSize
from rockmass.dfn.validation import compare_fit, virtual_face, virtual_scanline

SIZE = PowerLawSize(1.0, 20.0, 2.5)
SPECS = [FractureSetSpec(FisherOrientation(50, 270, 20), SIZE, IntensityP32(1.0), name="J1"),
         FractureSetSpec(FisherOrientation(80, 10, 20), SIZE, IntensityP32(1.0), name="J2"),
         FractureSetSpec(FisherOrientation(70, 150, 20), SIZE, IntensityP32(1.0), name="J3")]


def run(side: float, seed: int) -> dict:
    c = side / 2
    lines = [([2, c, c], [side - 2, c, c]), ([c, 2, c], [c, side - 2, c]), ([c, c, 2], [c, c, side - 2])]
    h = 0.375 * side
    window = [(-h, -h), (h, -h), (h, h), (-h, h)]
    t0 = time.perf_counter()
    net = generate(SPECS, [0, 0, 0, side, side, side], seed=seed)
    t1 = time.perf_counter()
    scans = [virtual_scanline(net, a, b) for a, b in lines]
    faces = [virtual_face(net, [c, c, c], m, window) for m in np.eye(3)]
    t2 = time.perf_counter()
    fit = fit_field(scans, faces, n_sets=3, size_family="power_law", r_max_m=20.0)
    t3 = time.perf_counter()
    rows = compare_fit(fit, SPECS, net)

    def worst(quantity, scale=1.0):
        return max(abs(r["error"]) / (r["true"] if scale is None else scale) for r in rows if r["quantity"] == quantity)

    return {"side_m": side, "seed": seed, "disks": net.n_fractures, "hits": sum(s.n_intersections for s in scans),
            "traces": sum(f.trace_map.n_traces for f in faces), "generate_s": t1 - t0, "sample_s": t2 - t1,
            "fit_s": t3 - t2, "pole_deg": worst("mean_pole_deg"), "kappa_rel": worst("kappa", None),
            "p32_rel": worst("p32", None), "alpha_abs": worst("size.alpha"),
            "passed": f"{sum(r['ok'] for r in rows)}/{len(rows)}"}


def main() -> None:
    generate(SPECS, [0, 0, 0, 10, 10, 10], seed=0)          # warm numba (compile or cache load)
    rows = [run(side, seed) for side in (20.0, 40.0, 80.0) for seed in (1, 2)]
    print(header("DFN closed loop: generate -> scanlines + faces -> fit -> compare (3 sets, power law)"))
    print(table(rows, [("side_m", ".0f"), ("seed", "d"), ("disks", "d"), ("hits", "d"), ("traces", "d"),
                       ("generate_s", ".3f"), ("sample_s", ".3f"), ("fit_s", ".2f"), ("pole_deg", ".2f"),
                       ("kappa_rel", ".3f"), ("p32_rel", ".3f"), ("alpha_abs", ".3f"), ("passed", "s")]))
    print(f"results: {save('bench_dfn_validate', {'rows': rows})}")


if __name__ == "__main__":
    main()
