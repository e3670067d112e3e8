"""``rockmass dfn CONFIG --out DIR``: seeded disk-network realizations from the ``[dfn]`` section.

For each realization i (``--first I`` .. ``I + K - 1``, K from ``--realizations`` or the config)
writes ``realization_NNNN/fractures.csv`` (``set,cx,cy,cz,nx,ny,nz,radius``),
``realization_NNNN/fractures.vtu`` (the disks' polygons clipped to the domain, cell data ``set``, ``id``,
``dip_deg``, ``dip_direction_deg``, ``radius_m``, ``clipped``; :mod:`rockmass.dfn.network_io`), with
``[[dfn.sections]]`` ``realization_NNNN/sections.vtu`` (the section traces as lines) and
``realization_NNNN/summary.json`` (target and achieved P32, P30 and counts per set), and one top-level
``manifest.json``. Everything is computed first and written all-or-nothing. Realization i depends only
on the root seed and i (docs/design.md §3.5), so ``--first 7 --realizations 1`` reproduces realization 7 of
any batch, on any worker. CONFIG may hold other stages' sections too (a ``[blocks]`` cut by a
``[blocks.dfn_section]`` of these sets, say): the whole file is validated and ``[dfn]`` runs.

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
from .outputs import print_json

__all__ = ["add_parser", "document", "run", "summary_text"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``dfn`` subcommand."""
    p = subparsers.add_parser(
        "dfn", help="generate seeded DFN realizations (disks) from a config",
        description="Poisson disk fracture networks filled to each set's clipped P32 target; "
                    "reproducible by seed and realization index.")
    p.add_argument("config", help="TOML file with a [dfn] section (its other sections are "
                                  "validated, not run)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", type=int, help="root seed (overrides dfn.seed)")
    p.add_argument("--realizations", type=int, help="number of realizations (overrides dfn.realizations)")
    p.add_argument("--first", type=int, default=0, help="index of the first realization (default 0)")
    p.add_argument("--json", action="store_true",
                   help="print the fitted sets (with [dfn.fit]) and every realization's summary as JSON "
                        "on stdout")
    p.set_defaults(handler=run)
    return p


def document(seed, results, fit) -> dict:
    """The ``--json`` document: root seed, ``fitted`` (fitted.json's content, None without
    ``[dfn.fit]``) and per realization its index, summary.json and validation.json (None without
    ``validate``): what the files hold."""
    from .dfn_stage import validation_document

    return {"seed": seed, "fitted": None if fit is None else fit.as_dict(),
            "realizations": [{"index": index, "summary": summary,
                              "validation": validation_document(rows, index) if rows else None}
                             for index, _, summary, rows in results]}


def summary_text(seed, results, fit) -> str:
    """The lines printed without ``--json``: fitted sets, then one line per realization."""
    from .dfn.orientation import dip_text

    lines = []
    if fit is not None:
        for s in fit.sets:
            size = "no size law" if s.size is None or not s.size.ok else s.size.family
            lines.append(f"fitted {s.name}: dip/dip direction {dip_text(s.mean_dip_deg, s.mean_dip_direction_deg)}, "
                         f"kappa {s.kappa:.3g}, P32 {s.p32:.4g} ± {s.p32_sd:.2g} m²/m³, {size}")
            if s.size is not None and s.size.ok and s.size.note:
                lines.append(f"  note: {s.name} size: {s.size.note}")
    for index, _, summary, rows in results:
        total = summary["total"]
        check = "" if not rows else f"; validation {sum(r['ok'] for r in rows)}/{len(rows)} within tolerance"
        lines.append(f"realization {index}: {total['count']} fractures, P32 {total['achieved_p32']:.4g} "
                     f"(target {total['target_p32']:.4g}) m²/m³{check}")
        for sec in summary.get("sections", []):
            sd = "" if sec["p21_sd"] is None else f" ± {sec['p21_sd']:.2g}"
            lines.append(f"  {sec['name']}: {sec['traces']} traces, P21 {sec['p21']:.4g}{sd} m/m² "
                         f"(expected P32/C23 {sec['p21_expected']:.4g})")
    return "\n".join(lines)


def run(args) -> int:
    """Handler of ``rockmass dfn``."""
    _, _, seed, results, _, fit = produce(args, args.out)
    if args.json:
        print_json(document(seed, results, fit))
    else:
        print(summary_text(seed, results, fit))
    return 0
