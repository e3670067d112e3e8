"""``rockmass run CONFIG --out DIR``: the whole chain, or the stages the config asks for.

The stages (``extract``, ``traces``, ``boxcount``, ``scanline``, ``dfn``, ``blocks``, ``solve``) are
the single-stage subcommands composed: each reads its usual config section and writes into
``DIR/<stage>/`` exactly what that subcommand writes into its ``--out``, plus ``stage.json`` (its
content hash). Then ``DIR/run.json`` (stages, status ran / reused, hashes, wall times, outputs),
``DIR/report.html`` and ``DIR/manifest.json`` (every file with its SHA-256). ``[run]`` names the field
inputs; :mod:`rockmass.run_config` states how a stage feeds the next, :mod:`rockmass.run` how stages
are reused. ``--force`` recomputes every stage; ``--json`` prints run.json. Logs and progress bars
go to stderr (bars only on a terminal; ``ROCKMASS_QUIET=1`` turns them off).
"""

from __future__ import annotations

import argparse

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``run`` subcommand."""
    p = subparsers.add_parser(
        "run", help="the whole chain (photo / traces / scanline -> ... -> DEM), reusing unchanged stages",
        description="Run the stages a config asks for ([run] inputs; [imaging], [fractal], [dfn], "
                    "[blocks], [solve] settings) into DIR/<stage>/, reusing every stage whose "
                    "settings and inputs are unchanged; run.json, report.html, manifest.json.")
    p.add_argument("config", help="TOML file with a [run] section")
    p.add_argument("--out", required=True, help="output folder (stage folders, run.json, report.html, "
                                                "manifest.json)")
    p.add_argument("--force", action="store_true", help="recompute every stage (no reuse)")
    p.add_argument("--json", action="store_true", help="print run.json on stdout")
    p.set_defaults(handler=run)
    return p


def run(args) -> int:
    """Handler of ``rockmass run``."""
    from .outputs import print_json
    from .run import execute, plan_run

    plan = plan_run(args.config, args.out)  # every check before any stage runs
    document = execute(plan, force=args.force, argv=args.argv)
    if args.json:
        print_json(document)
    else:
        ran = [s["name"] for s in document["stages"] if s["status"] == "ran"]
        reused = [s["name"] for s in document["stages"] if s["status"] == "reused"]
        print(f"{len(document['stages'])} stages in {document['total_wall_s']:.1f} s: ran "
              f"{', '.join(ran) or 'none'}; reused {', '.join(reused) or 'none'}; outputs in {args.out}")
    return 0
