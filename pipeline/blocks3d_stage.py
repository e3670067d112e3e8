"""The work of ``rockmass blocks3d``: a 3D block model from the ``[blocks3d]`` section.

:func:`compute` loads and validates the config, generates the DFN realization when the section asks
for one (from the ``[dfn]`` sets of the same file, in the block box), and builds the model
(:func:`rockmass.blockgen.model3d.build3d`); :func:`produce` also writes, into a folder, all of them
or none: ``blocks3d.vtu`` (every face, with its block, keyblock mode and factor of safety),
``blocks.csv`` (one row per in-situ block: volume, area, ellipsoid semi-axes, elongation, flatness,
sphericity, centroid), ``keyblocks.csv`` (one row per block with a free face), ``summary.json``
(counts, volume balance, tiny and sliver pieces, the block volume distribution with its
lognormal fit, keyblock modes) and ``manifest.json``.
"""

from __future__ import annotations

import time
from collections import Counter

from .errors import ConfigError, InputError
from .outputs import output_folder

__all__ = ["compute", "produce", "summary"]

def _network(document, settings, config_path):
    """The DFN realization of ``[dfn]`` in the block box, or None."""
    if settings.dfn_realization is None:
        return None
    from .dfn import generate

    dfn = document.dfn
    if dfn is None or not dfn.sets:
        raise ConfigError(config_path, [("blocks3d.dfn_realization", "needs [[dfn.sets]] in the same "
                                         "file (the sets to generate the fractures from)")])
    try:
        return generate([s.to_spec() for s in dfn.sets], [settings.box_min_m, settings.box_max_m],
                        seed=dfn.seed, realization=settings.dfn_realization,
                        max_fractures=dfn.max_fractures)
    except ValueError as exc:
        raise InputError(f"{config_path}: blocks3d.dfn_realization: {exc}") from exc


def compute(args, document=None):
    """Load (unless given), validate, generate and build; return (document, model, timings)."""
    from .blockgen.model3d import build3d
    from .config import load_config, required_section

    t0 = time.perf_counter()
    if document is None:
        document = load_config(args.config)
    settings = required_section(document, "blocks3d", args.config).to_library()
    network = _network(document, settings, args.config)
    t1 = time.perf_counter()
    model = build3d(settings, network)
    t2 = time.perf_counter()
    return document, model, {"load_and_dfn_s": t1 - t0, "build_s": t2 - t1}


def summary(model) -> dict:
    """Counts, volume balance, piece quality, the block volume distribution (quantiles and lognormal
    fit) and keyblock modes, as plain JSON types."""
    from dataclasses import asdict

    import numpy as np

    from .blockgen.block_shapes import piece_quality, volume_distribution

    blocks = model.blocks
    box_volume = float(np.prod(blocks.box_m[1] - blocks.box_m[0]))
    modes = Counter(k.mode for k in model.keyblocks)
    finite = [k.factor_of_safety for k in model.keyblocks if k.mode in ("slide", "slide2")]
    return {
        "pieces": len(blocks.pieces), "blocks": blocks.n_blocks,
        "excavated_pieces": int(blocks.excavated.sum()),
        "excavated_volume_m3": float(blocks.volume_m3[blocks.excavated].sum()),
        "volume_balance": float(abs(blocks.volume_m3.sum() / box_volume - 1.0)),
        "piece_quality": asdict(piece_quality(blocks)),
        "block_volume_m3": asdict(volume_distribution(model.shapes.volume_m3)),
        "keyblocks": {"with_free_face": len(model.keyblocks), "modes": dict(sorted(modes.items())),
                      "smallest_sliding_factor_of_safety": min(finite) if finite else None},
    }


def _csv(rows: list[list], header: list[str]) -> str:
    return "\n".join([",".join(header)] + [",".join(format(v, ".6g") if isinstance(v, float) else str(v)
                                                    for v in row) for row in rows]) + "\n"


def _blocks_csv(model) -> str:
    s = model.shapes
    rows = [[b, s.volume_m3[b], s.surface_area_m2[b], *s.semi_axes_m[b], s.elongation[b], s.flatness[b],
             s.sphericity[b], *s.centroid_m[b]] for b in range(len(s.volume_m3))]
    return _csv([[int(r[0]), *map(float, r[1:])] for r in rows],
                ["block", "volume_m3", "surface_area_m2", "a_m", "b_m", "c_m", "elongation", "flatness",
                 "sphericity", "x_m", "y_m", "z_m"])


def _keyblocks_csv(model) -> str:
    rows = [[k.block, k.mode, k.volume_m3, k.free_area_m2, k.apex_height_m,
             "inf" if k.factor_of_safety == float("inf") else float(k.factor_of_safety),
             " ".join(map(str, k.planes)), *map(float, k.direction)] for k in model.keyblocks]
    return _csv(rows, ["block", "mode", "volume_m3", "free_area_m2", "apex_height_m", "factor_of_safety",
                       "planes", "dx", "dy", "dz"])


def produce(args, out_dir, document=None):
    """Build (:func:`compute`) and write every output into ``out_dir``; return what :func:`compute`
    returns plus the summary."""
    from contextlib import ExitStack

    from .atomic import atomic_path, atomic_write_json, atomic_write_text
    from .blockgen.blocks3d_io import write_blocks3d_vtu
    from .manifest import build_manifest

    document, model, timings = compute(args, document)
    doc = summary(model)
    with output_folder(out_dir) as out, ExitStack() as stack:
        paths = {name: stack.enter_context(atomic_path(out / name)) for name in
                 ("blocks3d.vtu", "blocks.csv", "keyblocks.csv", "summary.json", "manifest.json")}
        write_blocks3d_vtu(model.blocks, paths["blocks3d.vtu"], model.keyblocks)
        atomic_write_text(paths["blocks.csv"], _blocks_csv(model))
        atomic_write_text(paths["keyblocks.csv"], _keyblocks_csv(model))
        atomic_write_json(paths["summary.json"], doc)
        seeds = None
        if document.blocks3d.dfn_realization is not None:
            seeds = {"dfn.seed": document.dfn.seed, "realization": document.blocks3d.dfn_realization}
        manifest = build_manifest(command=args.argv, config=document, inputs=[args.config], seeds=seeds,
                                  timings_s=timings)
        atomic_write_json(paths["manifest.json"], manifest)
    return document, model, doc
