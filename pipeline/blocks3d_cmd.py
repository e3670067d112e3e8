"""``rockmass blocks3d CONFIG --out DIR``: 3D blocks, keyblocks and block sizes from ``[blocks3d]``.

Writes under ``--out``: ``blocks3d.vtu``, ``blocks.csv``, ``keyblocks.csv``, ``keyblocks.png``,
``summary.json`` and ``manifest.json`` — all of them or none (:mod:`rockmass.blocks3d_stage`); with ``--realizations K``
one ``realization_NNNN/`` folder each, ``realizations.csv`` and the spread in ``summary.json``.
``--json`` prints the summary.
"""

from __future__ import annotations

import argparse

from .blocks3d_stage import produce
from .outputs import print_summary

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``blocks3d`` subcommand."""
    p = subparsers.add_parser(
        "blocks3d", help="3D blocks from joint sets or a DFN, keyblocks around tunnels, block sizes",
        description="Cut a box into convex polyhedra by persistent joint sets and/or a DFN "
                    "realization, excavate tunnels, and analyse block sizes and keyblocks.")
    p.add_argument("config", help="TOML file with a [blocks3d] section (and [dfn] for a DFN)")
    p.add_argument("--out", required=True, help="write blocks3d.vtu, blocks.csv, keyblocks.csv, "
                                                "keyblocks.png, summary.json and manifest.json here")
    p.add_argument("--realizations", type=int, default=1, metavar="K",
                   help="build DFN realizations dfn_realization .. dfn_realization + K - 1, each in "
                        "realization_NNNN/, with realizations.csv and their spread in summary.json "
                        "(default 1)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(handler=run)
    return p


def _text(doc: dict) -> str:
    if "across" in doc:
        a = doc["across"]
        return (f"{len(doc['realizations'])} realizations: {a['blocks']['mean']:.0f} ± "
                f"{a['blocks']['sd']:.0f} in-situ blocks, median block {a['median_block_m3']['mean']:.3g} ± "
                f"{a['median_block_m3']['sd']:.2g} m³, {a['blocks_on_openings']['mean']:.1f} blocks on the "
                "openings (realizations.csv, summary.json)")
    modes = ", ".join(f"{k} {v}" for k, v in doc["keyblocks"]["modes"].items()) or "none"
    q = doc["block_volume_m3"]["quantiles"]
    median = f"; median block {q['0.5']:.3g} m³" if q else ""
    return (f"{doc['blocks']} in-situ blocks from {doc['pieces']} convex pieces{median}; volume "
            f"balance {doc['volume_balance']:.1e}; {doc['keyblocks']['with_free_face']} blocks on the "
            f"openings: {modes}")


def run(args) -> int:
    """Handler of ``rockmass blocks3d``."""
    _, _, doc = produce(args, args.out)
    print_summary(doc, args.json, _text)
    return 0
