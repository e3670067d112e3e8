"""The work of ``rockmass blocks3d``: a 3D block model from the ``[blocks3d]`` section.

:func:`compute` loads and validates the config, generates the DFN realization when the section asks
for one (from the ``[dfn]`` sets of the same file, in the block box), and builds the model
(:func:`rockmass.blockgen.model3d.build3d`); :func:`produce` also writes, into a folder, all of them
or none (one folder per realization when ``--realizations`` asks for several): ``blocks3d.vtu``
(every face, with its block, keyblock mode and factor of safety),
``blocks.csv`` (one row per in-situ block: volume, area, ellipsoid semi-axes, elongation, flatness,
sphericity, centroid), ``keyblocks.csv`` (one row per block with a free face), ``keyblocks.png`` (the blocks that can
fall or slide, in 3D), ``summary.json``
(counts, volume balance, tiny and sliver pieces, the block volume distribution with its
lognormal fit, keyblock modes) and ``manifest.json``.
"""

from __future__ import annotations

import time
from collections import Counter

from .errors import ConfigError, InputError
from .outputs import csv_text, output_set

__all__ = ["compute", "produce", "summary"]

#: names ``rockmass blocks3d`` writes in either layout (one realization or several), so a set
#: of the other layout left in --out is replaced, not mixed with the new one.
_OWNED = (r"realization_\d{4,}", r"realizations\.csv", r"blocks3d\.vtu", r"keyblocks\.(png|csv)",
          r"blocks\.csv")

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


#: the most realizations one command builds (each is a full block model).
MAX_REALIZATIONS = 1000


def _dfn_counts(document, settings) -> list[float]:
    """Expected disks of each ``[dfn]`` set that a DFN realization draws around the box
    (:func:`rockmass.dfn.generation.expected_counts`); empty without a DFN or with a bad set (the
    generator says which)."""
    from .dfn.generation import expected_counts

    if settings.dfn_realization is None or document.dfn is None or not document.dfn.sets:
        return []
    try:
        specs = [s.to_spec() for s in document.dfn.sets]
        return [float(n) for n in expected_counts(specs, [settings.box_min_m, settings.box_max_m])]
    except ValueError:
        return []


def _check_memory_budget(config_path, document, settings, count: int) -> None:
    """Refuse, before any fracture is drawn or piece cut, models whose pieces need more memory than
    the limit (:mod:`rockmass.budgets`; every realization's model is held until the outputs are
    written), naming the field that makes most of them: the densest persistent set or the DFN set
    with the most disks.

    Pieces: those of the persistent sets (:func:`rockmass.budgets.block3d_count_terms`) plus one
    per DFN disk drawn. A disk cuts every piece it touches by its whole plane, so the pieces of a
    DFN follow its disk count: measured 0.8 and 0.6 pieces per disk drawn (1297 pieces of 1631
    disks, tests' two-set DFN in a 6 m cube; 6457 of 10489, samples/blocks3d_seed001.toml)."""
    from .budgets import BLOCK3D_BYTES, block3d_count_terms, check_memory
    from .dfn.orientation import normal_from_dip

    disks = _dfn_counts(document, settings)
    if not settings.sets and not disks:
        return  # the box and its tunnels: a few pieces
    box = [settings.box_min_m, settings.box_max_m]
    terms = block3d_count_terms(box, [(normal_from_dip(j.dip_deg, j.dip_direction_deg), j.spacing_m)
                                      for j in settings.sets])
    persistent = sum(terms.values())
    pieces = 1.0 + persistent + sum(disks)
    if not settings.sets or sum(disks) > persistent:
        densest = max(range(len(disks)), key=disks.__getitem__)
        field = f"dfn.sets[{densest}].intensity"
    else:
        densest = min(range(len(settings.sets)), key=lambda i: settings.sets[i].spacing_m)
        field = f"blocks3d.sets[{densest}].spacing_m"
    check_memory(count * pieces * BLOCK3D_BYTES, f"{config_path}: {field}",
                 f"{count} model(s) of about {pieces:.3g} pieces ({persistent:.3g} from the "
                 f"persistent sets, {sum(disks):.3g} from DFN disks)",
                 "raise the spacings or lower the DFN intensity, make the box smaller or build "
                 "fewer realizations")


def _check_tunnels_reach_the_box(config_path, settings) -> None:
    """A tunnel that misses the box is a mistake (a centre in other coordinates, a swapped axis),
    refused as ``[blocks]`` refuses an excavation wholly outside its domain: built, it gave a model
    without the opening and without a word."""
    import itertools

    import numpy as np

    corners = np.array(list(itertools.product(*zip(settings.box_min_m, settings.box_max_m))), float)
    for k, spec in enumerate(settings.tunnels):
        if not spec.tunnel().reaches(corners, 0.0):
            raise ConfigError(config_path, [(f"blocks3d.tunnels[{k}]", f"({spec.name!r}) lies "
                                             f"wholly outside the box {list(settings.box_min_m)} .. "
                                             f"{list(settings.box_max_m)}; centre_m is in the "
                                             "box's frame (x East, y North, z up)")])


def compute(args, document=None):
    """Load (unless given), validate, generate and build; return (document, models, timings) with
    one model per realization (``args.realizations``, default 1: realizations ``dfn_realization``,
    ``dfn_realization + 1``, …)."""
    import dataclasses

    from .blockgen.model3d import build3d
    from .config import load_config, required_section

    t0 = time.perf_counter()
    if document is None:
        document = load_config(args.config)
    settings = required_section(document, "blocks3d", args.config).to_library()
    t_loaded = time.perf_counter()
    count = getattr(args, "realizations", None) or 1
    if not 1 <= count <= MAX_REALIZATIONS:
        raise InputError(f"--realizations must be in 1..{MAX_REALIZATIONS}, got {count}")
    if count > 1 and settings.dfn_realization is None:
        raise ConfigError(args.config, [("blocks3d.dfn_realization", f"--realizations {count} needs "
                                         "a DFN: set the first realization here")])
    _check_tunnels_reach_the_box(args.config, settings)
    _check_memory_budget(args.config, document, settings, count)
    models, t_dfn, t_build = [], 0.0, 0.0
    for k in range(count):
        t1 = time.perf_counter()
        one = (settings if settings.dfn_realization is None else
               dataclasses.replace(settings, dfn_realization=settings.dfn_realization + k))
        network = _network(document, one, args.config)
        t2 = time.perf_counter()
        models.append(build3d(one, network))
        t_dfn += t2 - t1
        t_build += time.perf_counter() - t2
    return document, models, {"load_s": t_loaded - t0, "dfn_s": t_dfn, "build_s": t_build}


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


def _blocks_csv(model) -> str:
    import numpy as np

    s = model.shapes
    a, b, c = s.semi_axes_m.T
    x, y, z = s.centroid_m.T
    return csv_text({"block": np.arange(len(s.volume_m3)), "volume_m3": s.volume_m3,
                     "surface_area_m2": s.surface_area_m2, "a_m": a, "b_m": b, "c_m": c,
                     "elongation": s.elongation, "flatness": s.flatness, "sphericity": s.sphericity,
                     "x_m": x, "y_m": y, "z_m": z})


def _keyblocks_csv(model) -> str:
    import numpy as np

    k = model.keyblocks
    direction = np.array([r.direction for r in k]).reshape(-1, 3)
    return csv_text({"block": [r.block for r in k], "mode": [r.mode for r in k],
                     "volume_m3": [r.volume_m3 for r in k], "free_area_m2": [r.free_area_m2 for r in k],
                     "apex_height_m": [r.apex_height_m for r in k],
                     "factor_of_safety": [r.factor_of_safety for r in k],
                     "planes": [" ".join(map(str, r.planes)) for r in k],
                     "dx": direction[:, 0], "dy": direction[:, 1], "dz": direction[:, 2]})


#: the per-realization numbers compared across realizations (summary.json "across").
_ACROSS = {"blocks": ("blocks",), "median_block_m3": ("block_volume_m3", "quantiles", "0.5"),
           "log_mean": ("block_volume_m3", "log_mean"), "log_sd": ("block_volume_m3", "log_sd"),
           "blocks_on_openings": ("keyblocks", "with_free_face")}


def _across(docs: list[dict]) -> dict:
    """Mean, standard deviation, min and max over realizations of each number in :data:`_ACROSS`,
    and of the count of each keyblock mode."""
    import numpy as np

    def pick(doc, path):
        for key in path:
            doc = doc[key]
        return doc

    columns = {name: [float(pick(d, path)) for d in docs] for name, path in _ACROSS.items()}
    modes = sorted({m for d in docs for m in d["keyblocks"]["modes"]})
    columns.update({f"mode_{m}": [float(d["keyblocks"]["modes"].get(m, 0)) for d in docs] for m in modes})
    return {name: {"mean": float(np.mean(v)), "sd": float(np.std(v, ddof=1)) if len(v) > 1 else 0.0,
                   "min": float(np.min(v)), "max": float(np.max(v))} for name, v in columns.items()}


def _model_files(model, doc: dict) -> dict:
    """name -> writer(path) of one model's files."""
    from .atomic import atomic_write_json, atomic_write_text
    from .blockgen.blocks3d_io import write_blocks3d_vtu

    from .blockgen.plots3d import plot_keyblocks

    return {"blocks3d.vtu": lambda path: write_blocks3d_vtu(model.blocks, path, model.keyblocks),
            "keyblocks.png": lambda path: plot_keyblocks(model.blocks, model.keyblocks, path),
            "blocks.csv": lambda path: atomic_write_text(path, _blocks_csv(model)),
            "keyblocks.csv": lambda path: atomic_write_text(path, _keyblocks_csv(model)),
            "summary.json": lambda path: atomic_write_json(path, doc)}


def produce(args, out_dir, document=None):
    """Build (:func:`compute`) and write every output into ``out_dir``, all of them or none; return
    ``(document, models, summary document)``.

    One realization: ``blocks3d.vtu``, ``blocks.csv``, ``keyblocks.csv``, ``keyblocks.png``,
    ``summary.json``, ``manifest.json``. Several: ``realization_NNNN/`` with the first five for each,
    ``realizations.csv`` (one row per realization) and ``summary.json`` with each realization's
    summary and their spread (``across``), and ``manifest.json``.
    """
    from contextlib import ExitStack

    from .atomic import atomic_path, atomic_write_json, atomic_write_text
    from .manifest import build_manifest

    document, models, timings = compute(args, document)
    docs = [summary(m) for m in models]
    first = document.blocks3d.dfn_realization
    if len(models) == 1:
        files = _model_files(models[0], docs[0])
        doc = docs[0]
    else:
        files = {}
        for k, (model, one) in enumerate(zip(models, docs)):
            files.update({f"realization_{first + k:04d}/{name}": write
                          for name, write in _model_files(model, one).items()})
        doc = {"realizations": [{"realization": first + k, **d} for k, d in enumerate(docs)],
               "across": _across(docs)}
        files["realizations.csv"] = lambda path: atomic_write_text(path, _realizations_csv(first, docs))
        files["summary.json"] = lambda path: atomic_write_json(path, doc)
    with output_set(out_dir, owns=_OWNED) as out, ExitStack() as stack:
        paths = {name: stack.enter_context(atomic_path(out / name)) for name in [*files, "manifest.json"]}
        for name, write in files.items():
            write(paths[name])
        seeds = None
        if first is not None:
            seeds = {"dfn.seed": document.dfn.seed, "realizations": list(range(first, first + len(models)))}
        manifest = build_manifest(command=args.argv, config=document, inputs=[args.config], seeds=seeds,
                                  timings_s=timings)
        atomic_write_json(paths["manifest.json"], manifest)
    return document, models, doc


def _realizations_csv(first: int, docs: list[dict]) -> str:
    modes = sorted({m for d in docs for m in d["keyblocks"]["modes"]})
    volumes = [d["block_volume_m3"] for d in docs]
    return csv_text({"realization": [first + k for k in range(len(docs))],
                     "pieces": [d["pieces"] for d in docs], "blocks": [d["blocks"] for d in docs],
                     "median_block_m3": [v["quantiles"].get("0.5", 0.0) for v in volumes],
                     "log_mean": [v["log_mean"] for v in volumes], "log_sd": [v["log_sd"] for v in volumes],
                     "volume_balance": [d["volume_balance"] for d in docs],
                     "blocks_on_openings": [d["keyblocks"]["with_free_face"] for d in docs],
                     **{f"mode_{m}": [d["keyblocks"]["modes"].get(m, 0) for d in docs] for m in modes}})
