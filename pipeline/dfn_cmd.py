"""``rockmass dfn CONFIG --out DIR``: seeded disk-network realizations from the ``[dfn]`` section.

For each realization i (``--first I`` .. ``I + K - 1``, K from ``--realizations`` or the config)
writes ``realization_NNNN/fractures.csv`` (``set,cx,cy,cz,nx,ny,nz,radius``),
``realization_NNNN/fractures.vtu`` (polygons with ``set`` and ``id`` cell data) and
``realization_NNNN/summary.json`` (target and achieved P32, P30 and counts per set), and one top-level
``manifest.json``. Everything is computed first and written all-or-nothing. Realization i depends only
on the root seed and i (docs/design.md §3.5), so ``--first 7 --realizations 1`` reproduces realization 7 of
any batch, on any worker.

With ``[dfn.fit]`` the sets are first fitted from the field data the config names (scanlines and face
trace maps, :func:`rockmass.dfn.fit_field`): ``fitted.json`` holds every fitted parameter with its
standard deviation and the size candidates compared by AIC. With ``validate = true`` each realization
is re-sampled with the field geometry and ``realization_NNNN/validation.json`` compares measured and
re-sampled P10, P21, mean trace length and set orientations, each with a Poisson-based tolerance
(:func:`rockmass.dfn.validation.compare_with_field`).
"""

from __future__ import annotations

import argparse

from .dfn_stage import produce

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``dfn`` subcommand."""
    p = subparsers.add_parser(
        "dfn", help="generate seeded DFN realizations (disks) from a config",
        description="Poisson disk fracture networks filled to each set's clipped P32 target; "
                    "reproducible by seed and realization index.")
    p.add_argument("config", help="TOML file with a [dfn] section")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", type=int, help="root seed (overrides dfn.seed)")
    p.add_argument("--realizations", type=int, help="number of realizations (overrides dfn.realizations)")
    p.add_argument("--first", type=int, default=0, help="index of the first realization (default 0)")
    p.set_defaults(handler=run)
    return p


def run(args) -> int:
    """Handler of ``rockmass dfn``."""
    _, _, _, results, _, fit = produce(args, args.out)
    if fit is not None:
        for s in fit.sets:
            size = "no size law" if s.size is None or not s.size.ok else s.size.family
            print(f"fitted {s.name}: dip {s.mean_dip_deg:.1f}/{s.mean_dip_direction_deg:05.1f}, kappa "
                  f"{s.kappa:.3g}, P32 {s.p32:.4g} ± {s.p32_sd:.2g} m²/m³, {size}")
    for index, _, summary, rows in results:
        total = summary["total"]
        check = "" if not rows else f"; validation {sum(r['ok'] for r in rows)}/{len(rows)} within tolerance"
        print(f"realization {index}: {total['count']} fractures, P32 {total['achieved_p32']:.4g} "
              f"(target {total['target_p32']:.4g}) m²/m³{check}")
        for sec in summary.get("sections", []):
            sd = "" if sec["p21_sd"] is None else f" ± {sec['p21_sd']:.2g}"
            print(f"  {sec['name']}: {sec['traces']} traces, P21 {sec['p21']:.4g}{sd} m/m² "
                  f"(expected P32/C23 {sec['p21_expected']:.4g})")
    return 0
