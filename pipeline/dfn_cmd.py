"""``rockmass dfn CONFIG --out DIR``: seeded disk-network realizations from the ``[dfn]`` section.

For each realization i (``--first I`` .. ``I + K - 1``, K from ``--realizations`` or the config)
writes ``realization_NNNN/fractures.csv`` (``set,cx,cy,cz,nx,ny,nz,radius``),
``realization_NNNN/fractures.vtu`` (polygons with ``set`` and ``id`` cell data) and
``realization_NNNN/summary.json`` (target and achieved P32, P30 and counts per set), and one top-level
``manifest.json``. Everything is computed first and written all-or-nothing. Realization i depends only
on the root seed and i (DESIGN.md §3), so ``--first 7 --realizations 1`` reproduces realization 7 of
any batch, on any worker.
"""

from __future__ import annotations

import argparse
import time

from .errors import InputError
from .outputs import output_folder

__all__ = ["add_parser", "run", "compute", "realization_summary"]


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


def _check_flag(value, flag: str, low: int) -> None:
    if value is not None and value < low:
        raise InputError(f"{flag} must be >= {low}, got {value}")


def realization_summary(network, specs, seed: int, index: int) -> dict:
    """Target and achieved intensities of one realization, per set and in total."""
    sets = []
    for j, spec in enumerate(specs):
        sets.append({"set": j, "name": spec.name, "target_p32": spec.p32,
                     "achieved_p32": network.p32(j), "p30": network.p30(j),
                     "count": int((network.set_id == j).sum())})
    return {"realization": index, "seed": seed, "spawn_key": [index],
            "domain_m": network.domain_m.tolist(), "volume_m3": network.volume_m3,
            "units": {"p32": "m2/m3 (one-sided)", "p30": "1/m3 (centres inside the domain)"},
            "sets": sets,
            "total": {"target_p32": sum(s["target_p32"] for s in sets), "achieved_p32": network.p32(),
                      "p30": network.p30(), "count": network.n_fractures}}


def compute(args):
    """Load, validate and generate; return (config, specs, seed, [(index, network, summary)], timings)."""
    from .config import load_config
    from .dfn_config import DFNDocument
    from .dfn.generation import generate

    _check_flag(args.seed, "--seed", 0)
    _check_flag(args.realizations, "--realizations", 1)
    _check_flag(args.first, "--first", 0)
    t0 = time.perf_counter()
    document = load_config(args.config, model=DFNDocument)
    cfg = document.dfn
    specs = []
    for j, set_cfg in enumerate(cfg.sets):
        try:
            specs.append(set_cfg.to_spec())
        except ValueError as exc:
            raise InputError(f"{args.config}: dfn.sets[{j}]: {exc}") from exc
    seed = cfg.seed if args.seed is None else args.seed
    count = cfg.realizations if args.realizations is None else args.realizations
    indices = list(range(args.first, args.first + count))
    results = []
    t1 = time.perf_counter()
    for i in indices:
        try:
            network = generate(specs, cfg.domain_m(), seed=seed, realization=i,
                               max_fractures=cfg.max_fractures)
        except ValueError as exc:
            raise InputError(f"{args.config}: dfn.max_fractures: {exc}") from exc
        results.append((i, network, realization_summary(network, specs, seed, i)))
    t2 = time.perf_counter()
    return document, specs, seed, results, {"load_s": t1 - t0, "generate_s": t2 - t1}


def run(args) -> int:
    """Handler of ``rockmass dfn``."""
    from contextlib import ExitStack

    from .atomic import atomic_path, atomic_write_json
    from .dfn.network_io import write_fractures_csv, write_fractures_vtu
    from .manifest import build_manifest

    document, specs, seed, results, timings = compute(args)
    t0 = time.perf_counter()
    with output_folder(args.out) as out, ExitStack() as stack:
        for index, network, summary in results:
            folder = out / f"realization_{index:04d}"
            paths = {name: stack.enter_context(atomic_path(folder / name))
                     for name in ("fractures.csv", "fractures.vtu", "summary.json")}
            write_fractures_csv(network, paths["fractures.csv"])
            write_fractures_vtu(network, paths["fractures.vtu"], n_vertices=[s.n_vertices for s in specs])
            atomic_write_json(paths["summary.json"], summary)
        manifest_path = stack.enter_context(atomic_path(out / "manifest.json"))
        timings["write_s"] = time.perf_counter() - t0
        manifest = build_manifest(
            command=args.argv, config=document, inputs=[args.config],
            seeds={"root": seed, "realizations": [r[0] for r in results],
                   "rule": "realization i: SeedSequence(root, spawn_key=(i,)); set j: spawn_key (i, j)"},
            timings_s=timings,
            extra={"counts": {f"realization_{i:04d}": s["total"]["count"] for i, _, s in results}})
        atomic_write_json(manifest_path, manifest)
    for index, _, summary in results:
        total = summary["total"]
        print(f"realization {index}: {total['count']} fractures, P32 {total['achieved_p32']:.4g} "
              f"(target {total['target_p32']:.4g}) m²/m³")
    return 0
