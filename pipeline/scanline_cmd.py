"""``rockmass scanline FILE``: joint sets, P10, spacings and RQD of a scanline survey.

Reads the survey with :func:`rockmass.dfn.read_scanline` (CSV with the line's trend, plunge and length
in ``# key: value`` header comments or in a TOML file beside it), finds the joint sets with
:func:`rockmass.dfn.sets3d.fit_sets_3d` (a bipolar Fisher mixture, k by BIC or ``--sets``), and
computes per set and for the whole line :func:`rockmass.dfn.scanline_stats.scanline_statistics`
(Fisher mean, κ, α95 and variability cones; P10 raw and Terzaghi-weighted with ``--terzaghi-cap``;
spacings with exponential and lognormal fits; RQD by Priest & Hudson and directly). Under
``--out DIR`` it writes ``summary.json``, ``stereonet.png`` and ``manifest.json`` — all of them or
none. ``--json`` prints the summary to stdout.
"""

from __future__ import annotations

import argparse

from .outputs import print_summary
from .scanline_stage import DEFAULT_SEED, produce

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``scanline`` subcommand."""
    p = subparsers.add_parser(
        "scanline", help="analyse a scanline survey (sets, P10, Terzaghi, spacings, RQD)",
        description="Joint sets (axial clustering of poles, Fisher statistics), P10 raw and "
                    "Terzaghi-weighted, spacing fits and RQD of a scanline survey CSV.")
    p.add_argument("file", help="scanline CSV: distance, dip, dip_direction (or strike, RHR), optional "
                                "trace_length, termination; '# trend: / # plunge: / # length:' header "
                                "comments or a .toml beside it")
    p.add_argument("--out", help="write summary.json, stereonet.png and manifest.json here")
    p.add_argument("--sets", type=int, dest="n_sets",
                   help="number of joint sets (default: chosen by BIC over 1-5)")
    p.add_argument("--terzaghi-cap", type=float, default=15.0, dest="terzaghi_cap_deg", metavar="DEG",
                   help="Terzaghi blind-zone angle in degrees: weights are capped at 1/sin(DEG) "
                        "(default 15)")
    p.add_argument("--seed", type=int, default=DEFAULT_SEED,
                   help=f"seed of the clustering's initialisations (default {DEFAULT_SEED})")
    p.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    p.set_defaults(handler=run)
    return p


def _fmt(value, fmt=".3g", unit=""):
    return "undefined" if value is None else f"{format(value, fmt)}{unit}"


def summary_text(summary: dict) -> str:
    """A few human-readable lines: the line, its totals and one line per set."""
    line, total = summary["scanline"], summary["all"]
    lines = [f"scanline {line['trend_deg']:.0f}/{line['plunge_deg']:.0f}, {line['length_m']:g} m: "
             f"{total['n_intersections']} joints, P10 = {total['p10_per_m']:.3g} /m "
             f"(Terzaghi {total['p10_terzaghi_per_m']:.3g} /m), RQD {total['rqd_direct_percent']:.1f} % "
             f"(Priest-Hudson {total['rqd_priest_hudson_percent']:.1f} %), "
             f"{summary['set_selection']['n_sets']} set(s) by {summary['set_selection']['selected_by']}"]
    from .dfn.orientation import dip_text

    for s in summary["sets"]:
        mean = ("mean undefined" if s["mean_dip_deg"] is None else
                dip_text(s["mean_dip_deg"], s["mean_dip_direction_deg"]))
        lines.append(f"  set {s['set']}: {mean}, kappa {_fmt(s['kappa'])}, a95 {_fmt(s['alpha95_deg'], '.1f', '°')}, "
                     f"{s['n_intersections']} hits, P10 {s['p10_per_m']:.3g} /m (Terzaghi "
                     f"{s['p10_terzaghi_per_m']:.3g}), mean spacing {_fmt(s['spacing_m']['mean_m'], '.3g', ' m')}")
    lines += [f"  warning: {w}" for w in summary["warnings"]]
    return "\n".join(lines)


def run(args) -> int:
    """Handler of ``rockmass scanline``."""
    print_summary(produce(args, args.out), args.json, summary_text)
    return 0
