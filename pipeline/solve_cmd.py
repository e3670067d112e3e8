"""``rockmass solve CONFIG --out DIR``: run the DEM (:func:`rockmass.solver.run`) from ``[solve]``.

The blocks come from ``solve.blocks_file`` (a ``blocks.json``) or from the ``[blocks]`` section of
the same file (built as ``rockmass blocks`` builds it). Writes under ``--out``:

- ``result.json``: the run's status and diagnostic, per stage (steps, time step, simulated time,
  convergence, unbalanced-force ratio, maximum displacements, slipping / open / broken contacts,
  detached blocks, energy ledger), the block kinetic energy vs volume table (Kiran & Juneja 2022, Fig. 7; docs/sources.md §2),
  per monitor its block, its displacement at the end of each stage and the largest plastic
  (slip) displacement on its contacts at the end, the frame list and timings;
- ``history.csv``: the monitored blocks over time (one column per quantity);
- ``blocks_NNNN.vtu`` per frame and ``blocks.pvd`` (ParaView time series), written by
  :mod:`rockmass.solver.vtu`: the polygons placed at each frame's positions and rotations, cell
  data ``displacement`` and ``velocity`` (3-vectors, z = 0, displacement from the model's original
  position), ``rotation_rad``, ``block_id``, ``region``, ``active``, ``failed`` (taken out because
  it kept moving), ``excavated`` (removed by its excavation stage). Frames at the same instant
  (the end of one stage and the start of the next, after its excavation) get times 1 ns apart in
  the ``.pvd`` so ParaView shows both; result.json has the exact times;
- ``block_energy.csv``: per block volume, mass, peak velocity and peak kinetic energy (dynamic
  stages);
- ``contacts.csv``: the active contacts at the end (stresses, plastic slip, slipping / broken);
- ``contacts.vtu``: the same contacts as ParaView points with stresses (compression positive), the
  force on ``block_b``, plastic slip, opening (the overlap sign-flipped) and flags
  (:func:`rockmass.solver.vtu.contact_mesh`);
- ``blocks.json``: the block model used; ``manifest.json``.

Everything is computed before the first file is written, and every file is written atomically. A
run that fails while stepping (status ``overlap`` or ``unstable``) still writes every file with its
status and diagnostic, then exits with code 1. Bad configuration exits with 2 naming the field.
"""

from __future__ import annotations

import argparse

from .errors import RunError
from .outputs import print_json
from .solve_stage import produce

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``solve`` subcommand."""
    p = subparsers.add_parser(
        "solve", help="run the distinct element solver on a block model (stages, loading)",
        description="Solve a block model with the DEM: joints, boundaries, in-situ stress, velocity "
                    "inputs, static / excavation / dynamic stages; result.json, history.csv, "
                    "ParaView frames.")
    p.add_argument("config", help="TOML file with a [solve] section (and blocks_file or [blocks])")
    p.add_argument("--out", required=True, help="write result.json, history.csv, blocks_NNNN.vtu, "
                                                "blocks.pvd, block_energy.csv, contacts.csv, contacts.vtu, "
                                                "blocks.json and manifest.json here")
    p.add_argument("--json", action="store_true", help="print the result summary as JSON")
    p.set_defaults(handler=run)
    return p


def _summary_line(result, doc) -> str:
    from .solver.failure import mechanism_counts

    parts = [f"status {result.status}"]
    for s in result.stages:
        text = (f"{s.name} ({s.kind}): {s.status}, {s.steps} steps of {s.time_step_s:.3g} s, "
                f"max displacement {s.max_displacement_equilibrium_m:.4g} m")
        if s.failed_blocks:
            text += (f", {len(s.failed_blocks)} failed block(s) taken out ("
                     + ", ".join(f"{k} {n}" for k, n in mechanism_counts(s.failed_blocks).items())
                     + ")")
        if s.monitors:
            text += ", " + ", ".join(f"{k} {v * 1e3:.3g} mm" for k, v in s.monitors.items())
        parts.append(text)
    for name, m in doc["monitors"].items():
        if "failed" in m:
            f = m["failed"]
            parts.append(f"monitor {name} (block {m['block']}): failed in stage {f['stage']} "
                         f"({f['mechanism']}, taken out after {f['displacement_at_removal_m']:.3g} m): "
                         f"no displacement")
        elif "final_ux_m" in m:
            parts.append(f"monitor {name} (block {m['block']}): u = ({m['final_ux_m']:.4g}, "
                         f"{m['final_uy_m']:.4g}) m")
    return "; ".join(parts)


def run(args) -> int:
    """Handler of ``rockmass solve``."""
    from .solver.result import FAILED_STATUSES

    result, doc = produce(args, args.out)
    if args.json:
        print_json({k: doc[k] for k in ("status", "diagnostic", "stages", "max_displacement_m",
                                         "monitors")})
    else:
        print(_summary_line(result, doc))
    if result.status in FAILED_STATUSES:
        raise RunError(f"{args.config}: the run stopped ({result.status}): {result.diagnostic}; "
                       f"everything computed so far is in {args.out} (result.json has the status)")
    return 0
