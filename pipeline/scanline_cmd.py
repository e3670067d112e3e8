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
import time
from pathlib import Path

from .errors import InputError
from .outputs import output_folder, print_summary

__all__ = ["add_parser", "run", "compute", "produce"]

#: Seed of the set clustering's initialisations (the fit is deterministic for a given seed).
DEFAULT_SEED = 0


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


def _check_args(args) -> None:
    if args.n_sets is not None and args.n_sets < 1:
        raise InputError(f"--sets must be >= 1 (number of joint sets), got {args.n_sets}")
    cap = args.terzaghi_cap_deg
    if not 0.0 < cap < 90.0:  # NaN fails too
        raise InputError(f"--terzaghi-cap must be in (0, 90) degrees, got {cap}")
    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")


def compute(args):
    """Read and analyse; return (summary dict, scanline, sets, timings)."""
    from .dfn.scanline import read_scanline
    from .dfn.scanline_stats import scanline_statistics
    from .dfn.sets3d import fit_sets_3d

    _check_args(args)
    t0 = time.perf_counter()
    try:
        scanline = read_scanline(Path(args.file))
    except OSError as exc:
        raise InputError(f"{exc.filename or args.file}: cannot read: {exc.strerror or exc}") from exc
    t1 = time.perf_counter()
    poles = scanline.poles()
    try:
        sets = fit_sets_3d(poles, n_sets=args.n_sets, seed=args.seed)
    except ValueError as exc:
        raise InputError(f"{args.file}: --sets: {exc}") from exc
    t2 = time.perf_counter()
    summary = scanline_statistics(scanline, sets.membership, sets.fits,
                                  terzaghi_cap_deg=args.terzaghi_cap_deg)
    t3 = time.perf_counter()
    summary["set_selection"] = {
        "n_sets": sets.n_sets, "selected_by": sets.selected_by, "seed": args.seed,
        "bic": {str(k): v for k, v in sets.bic.items()}, "converged": sets.converged,
        "method": "mixture of bipolar Fisher laws by EM (rockmass.dfn.sets3d)"}
    for entry, weight in zip(summary["sets"], sets.weight):
        entry["mixture_weight"] = float(weight)
    summary["membership"] = sets.membership.tolist()
    summary["input"] = {"path": str(args.file), "n_intersections": scanline.n_intersections}
    timings = {"read_s": t1 - t0, "sets_s": t2 - t1, "statistics_s": t3 - t2}
    return summary, scanline, sets, timings


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
    for s in summary["sets"]:
        mean = ("mean undefined" if s["mean_dip_deg"] is None else
                f"{s['mean_dip_deg']:.0f}/{s['mean_dip_direction_deg']:03.0f}")
        lines.append(f"  set {s['set']}: {mean}, kappa {_fmt(s['kappa'])}, a95 {_fmt(s['alpha95_deg'], '.1f', '°')}, "
                     f"{s['n_intersections']} hits, P10 {s['p10_per_m']:.3g} /m (Terzaghi "
                     f"{s['p10_terzaghi_per_m']:.3g}), mean spacing {_fmt(s['spacing_m']['mean_m'], '.3g', ' m')}")
    lines += [f"  warning: {w}" for w in summary["warnings"]]
    return "\n".join(lines)


def produce(args, out_dir=None):
    """Analyse, and write every output into the folder ``out_dir`` when given; return the summary.

    The work of ``rockmass scanline`` (and of the ``scanline`` stage of ``rockmass run``).
    """
    from contextlib import ExitStack

    summary, scanline, sets, timings = compute(args)
    if out_dir:
        from .atomic import atomic_path, atomic_write_json
        from .dfn.stereonet import plot_stereonet
        from .manifest import build_manifest

        inputs = [args.file]
        toml = Path(args.file).with_suffix(".toml")
        if toml.is_file():
            inputs.append(str(toml))
        # all files renamed into place only when every one is written
        with output_folder(out_dir) as out, ExitStack() as stack:
            paths = {name: stack.enter_context(atomic_path(out / name))
                     for name in ("stereonet.png", "summary.json", "manifest.json")}
            plot_stereonet(scanline.poles(), paths["stereonet.png"], membership=sets.membership,
                           set_fits=sets.fits, line_direction=scanline.direction,
                           title=f"{Path(args.file).name}: poles (lower hemisphere, equal area)")
            atomic_write_json(paths["summary.json"], summary)
            manifest = build_manifest(
                command=args.argv, inputs=inputs,
                config={"n_sets": args.n_sets, "terzaghi_cap_deg": args.terzaghi_cap_deg},
                seeds={"sets": args.seed}, timings_s=timings)
            atomic_write_json(paths["manifest.json"], manifest)
    return summary


def run(args) -> int:
    """Handler of ``rockmass scanline``."""
    print_summary(produce(args, args.out), args.json, summary_text)
    return 0
