"""The work of ``rockmass scanline`` and of the ``scanline`` stage of ``rockmass run``.

Joint sets, P10, spacings and RQD of a scanline survey: :func:`compute` checks the settings, reads
the survey, fits the sets and computes the statistics; :func:`produce` also writes ``summary.json``,
``stereonet.png`` and ``manifest.json`` into a folder, all of them or none.

The command (:mod:`rockmass.scanline_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import time
from pathlib import Path

from .errors import InputError, reads
from .outputs import output_set, plot_text

__all__ = ["DEFAULT_SEED", "compute", "produce"]

#: Seed of the set clustering's initialisations (the fit is deterministic for a given seed).
DEFAULT_SEED = 0


def _check_args(args) -> None:
    if args.n_sets is not None and args.n_sets < 1:
        raise InputError(f"--sets must be >= 1 (number of joint sets), got {args.n_sets}")
    cap = args.terzaghi_cap_deg
    if not 0.0 < cap < 90.0:  # NaN fails too
        raise InputError(f"--terzaghi-cap must be in (0, 90) degrees, got {cap}")
    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")


@reads("file")
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
        with output_set(out_dir) as out, ExitStack() as stack:
            paths = {name: stack.enter_context(atomic_path(out / name))
                     for name in ("stereonet.png", "summary.json", "manifest.json")}
            plot_stereonet(scanline.poles(), paths["stereonet.png"], membership=sets.membership,
                           set_fits=sets.fits, line_direction=scanline.direction,
                           title=f"{plot_text(Path(args.file).name)}: poles (lower hemisphere, equal area)")
            atomic_write_json(paths["summary.json"], summary)
            manifest = build_manifest(
                command=args.argv, inputs=inputs,
                config={"n_sets": args.n_sets, "terzaghi_cap_deg": args.terzaghi_cap_deg},
                seeds={"sets": args.seed}, timings_s=timings)
            atomic_write_json(paths["manifest.json"], manifest)
    return summary
