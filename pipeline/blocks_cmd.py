"""``rockmass blocks CONFIG --out DIR``: build a block model from the ``[blocks]`` section.

Writes under ``--out``: ``blocks.json`` (blocks, contacts, quality report; read back with
:func:`rockmass.blockgen.read_json`), ``blocks.vtu`` (polygons with block id, region and set),
``blocks.png`` and ``manifest.json`` — all of them or none. The config file may hold other stage
sections as well (:class:`rockmass.config.RockmassConfig`); every section is validated. Everything is computed (and the model's
invariants checked) before the first file is written. ``--json`` prints the quality report.
"""

from __future__ import annotations

import argparse

from .blocks_stage import produce
from .outputs import print_json

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``blocks`` subcommand."""
    p = subparsers.add_parser(
        "blocks", help="build a block model (joint sets or traces, excavations) from a config",
        description="Cut a 2D section by joint sets or traces, with excavation stages; convex "
                    "blocks, labelled contacts and a quality report.")
    p.add_argument("config", help="TOML file with a [blocks] section")
    p.add_argument("--out", required=True, help="write blocks.json, blocks.vtu, blocks.png and "
                                                "manifest.json here")
    p.add_argument("--json", action="store_true", help="print the quality report as JSON")
    p.set_defaults(handler=run)
    return p


def run(args) -> int:
    """Handler of ``rockmass blocks``."""
    _, model, _, _ = produce(args, args.out)
    q = model.quality
    if args.json:
        print_json(q.to_dict())
    else:
        regions = ", ".join(f"{k}: {v}" for k, v in q.n_blocks_by_region.items())
        print(f"{model.n_blocks} blocks ({regions}), "
              f"{model.n_contacts} contacts; area balance {q.area_balance['relative_error']:.2e}; "
              f"{len(q.slivers_merged)} slivers merged, {len(q.convex_splits)} concave blocks "
              f"split, {0 if q.edges_snapped is None else q.edges_snapped['count']} short edges "
              f"snapped; smallest edge {q.smallest_edge_m:.3g} m"
              + (f"; {q.cracks['n_crack_contacts']} potential cracks in "
                 f"{q.cracks['n_subdivided']} blocks" if q.cracks is not None else ""))
    return 0
