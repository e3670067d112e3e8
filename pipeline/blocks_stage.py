"""The work of ``rockmass blocks`` and of the ``blocks`` stage of ``rockmass run``.

A block model from the ``[blocks]`` section: :func:`compute` loads and validates the config, builds
the model (:func:`rockmass.blockgen.build`) and checks its invariants; :func:`produce` also writes
``blocks.json``, ``blocks.vtu``, ``blocks.png`` and ``manifest.json`` into a folder, all of them or
none. :func:`dfn_section_traces` generates the traces of ``[blocks.dfn_section]``.

The command (:mod:`rockmass.blocks_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import re
import time

from .errors import ConfigError, InputError, RunError, reading
from .inputs import read_trace_file
from .outputs import output_set

__all__ = ["dfn_section_traces", "compute", "produce"]

# library argument names -> config keys, for messages that name the field
_FIELD_NAMES = (("joint_sets[", "sets["), ("domain_xy_m", "domain"))


def _field_message(exc: Exception, two_sets: bool = False) -> str:
    text = str(exc)
    if two_sets:  # the joint sets came from [blocks.two_sets]: name its key, not a [[blocks.sets]]
        text = re.sub(r"^joint_sets\[(\d)\]", r"two_sets.spacing_m[\1]", text)
    for lib, cfg in _FIELD_NAMES:
        text = text.replace(lib, cfg)
    return text if re.match(r"^(blocks\.)", text) else f"blocks.{text}"


def dfn_section_traces(document, config_path):
    """(TraceMap, window) of ``[blocks.dfn_section]``: the named ``[[dfn.sections]]`` plane of the
    document's ``[dfn]`` section, generated on the plane (:func:`rockmass.dfn.generate_section`)."""
    from .dfn.orientation import normal_from_dip
    from .dfn.section import generate_section

    choice = document.blocks.dfn_section
    dfn = document.dfn
    if dfn is None:
        raise ConfigError(config_path, [("blocks.dfn_section", "needs the [dfn] section in the same "
                                         "file (its sets, seed and [[dfn.sections]])")])
    if not dfn.sets:
        raise ConfigError(config_path, [("blocks.dfn_section", "needs [[dfn.sets]] (sets fitted by "
                                         "[dfn.fit] are not supported here)")])
    names = [s.name for s in dfn.sections]
    if choice.section not in names:
        raise ConfigError(config_path, [("blocks.dfn_section.section", f"no [[dfn.sections]] entry "
                                         f"named {choice.section!r} (names: {names})")])
    if choice.realization >= dfn.realizations:
        raise ConfigError(config_path, [("blocks.dfn_section.realization", f"must be < "
                                         f"dfn.realizations ({dfn.realizations}), got "
                                         f"{choice.realization}")])
    sec = dfn.sections[names.index(choice.section)]
    try:
        traces = generate_section([s.to_spec() for s in dfn.sets], sec.point_m,
                                  normal_from_dip(sec.dip_deg, sec.dip_direction_deg), sec.window_uv_m,
                                  seed=dfn.seed, realization=choice.realization,
                                  max_fractures=dfn.max_fractures)
    except ValueError as exc:
        raise InputError(f"{config_path}: blocks.dfn_section: {exc}") from exc
    return traces, [tuple(p) for p in sec.window_uv_m]


def block_memory_estimate(cfg, domain_xy, joint_sets) -> tuple[float, str, str, str] | None:
    """Memory the blocks of ``[blocks]`` ``cfg`` need (:mod:`rockmass.budgets`): ``(bytes, field,
    what, fix)`` with the field that makes most of them (the spacings of the joint sets or the
    size of the cracks, each against the domain), what the estimate is made of and what to lower;
    None without a domain."""
    from .budgets import BLOCK_BYTES, block_count_terms

    if domain_xy is None:
        return None
    crack = cfg.cracks.size_m if cfg.cracks is not None else None
    terms = block_count_terms(domain_xy, [(j.angle_deg, j.spacing_m) for j in joint_sets], crack)
    total = 1.0 + sum(terms.values())
    if terms["cracks"] >= terms["lines"] + terms["crossings"]:
        field, fix = "blocks.cracks.size_m", "raise cracks.size_m or make the domain smaller"
    else:
        field = "blocks.two_sets.spacing_m" if cfg.two_sets is not None else "blocks.sets"
        fix = "raise the joint spacings or make the domain smaller"
    what = (f"about {total:.3g} blocks ({terms['crossings']:.3g} from joint crossings, "
            f"{terms['cracks']:.3g} from cracks)")
    return total * BLOCK_BYTES, field, what, fix


def _check_memory_budget(config_path, cfg, domain_xy, joint_sets) -> None:
    """Refuse, before building, a model whose blocks need more memory than the limit
    (:func:`block_memory_estimate`, :func:`rockmass.budgets.check_memory`)."""
    from .budgets import check_memory

    estimate = block_memory_estimate(cfg, domain_xy, joint_sets)
    if estimate is not None:
        needed, field, what, fix = estimate
        check_memory(needed, f"{config_path}: {field}", what, fix)


def compute(args, document=None, section=None):
    """Load (unless ``document`` is given), validate and build; return (document, model,
    invariants, timings).

    ``section``: ``(TraceMap, window)`` that replaces the traces of ``[blocks.dfn_section]`` (the
    ``run`` stage passes the section of its own DFN realization); files are relative to
    ``args.config``.
    """
    from .blockgen import build, check_model
    from .config import load_config, required_section

    t0 = time.perf_counter()
    # the whole document is validated (a file may hold other stages too); this command reads [blocks]
    if document is None:
        document = load_config(args.config)
    cfg = required_section(document, "blocks", args.config)
    traces = None
    path = cfg.traces_path(args.config)
    domain_xy = None if cfg.domain is None else cfg.domain.xy_m()
    try:
        joint_sets = cfg.joint_sets()
        excavations = [e.to_excavation() for e in cfg.excavations]
        if path is not None:
            with reading(path, "blocks.traces", config=args.config):
                traces = read_trace_file(path, "blocks.traces")
        if cfg.dfn_section is not None:
            traces, window = section or dfn_section_traces(document, args.config)
            domain_xy = window if domain_xy is None else domain_xy
        _check_memory_budget(args.config, cfg, domain_xy, joint_sets)
        t1 = time.perf_counter()
        model = build(domain_xy, joint_sets, traces, excavations, dangling=cfg.dangling,
                      seed=cfg.seed, rounding_m=cfg.rounding_m, min_edge_m=cfg.min_edge_m,
                      merge_slivers=cfg.merge_slivers, convex=cfg.convex, snap_edges=cfg.snap_edges,
                      cracks=cfg.cracks)
    except InputError:
        raise
    except ValueError as exc:
        raise InputError(f"{args.config}: {_field_message(exc, cfg.two_sets is not None)}") from exc
    t2 = time.perf_counter()
    invariants = check_model(model)
    if not invariants["ok"]:
        raise RunError(f"{args.config}: the block model fails its invariants {invariants} (a bug; "
                       "please report it with this config)")
    t3 = time.perf_counter()
    return document, model, invariants, {"load_s": t1 - t0, "build_s": t2 - t1, "check_s": t3 - t2}


def produce(args, out_dir, document=None, section=None):
    """Build (:func:`compute`) and write every output into the folder ``out_dir``; return what
    :func:`compute` returns.

    The work of ``rockmass blocks`` (and of the ``blocks`` stage of ``rockmass run``).
    """
    from contextlib import ExitStack

    from .atomic import atomic_path, atomic_write_json
    from .blockgen import plot_blocks, write_json, write_vtu
    from .manifest import build_manifest

    document, model, invariants, timings = computed = compute(args, document, section)
    inputs = [args.config]
    path = document.blocks.traces_path(args.config)
    if path is not None:
        inputs.append(str(path))
    with output_set(out_dir) as out, ExitStack() as stack:
        paths = {name: stack.enter_context(atomic_path(out / name))
                 for name in ("blocks.json", "blocks.vtu", "blocks.png", "manifest.json")}
        write_json(model, paths["blocks.json"])
        write_vtu(model, paths["blocks.vtu"])
        plot_blocks(model, paths["blocks.png"])
        seeds = {"root": document.blocks.seed,
                 "rule": "joint set i: SeedSequence(root).spawn(n)[i]; cracks: child n"}
        if document.blocks.dfn_section is not None:
            seeds["dfn_section"] = {"dfn.seed": document.dfn.seed,
                                    "realization": document.blocks.dfn_section.realization}
        manifest = build_manifest(command=args.argv, config=document, inputs=inputs, seeds=seeds,
                                  timings_s=timings, extra={"invariants": invariants})
        atomic_write_json(paths["manifest.json"], manifest)
    return computed
