"""``rockmass run``: the whole chain, any subset of its stages, with stage reuse by content hash.

A run is planned completely before anything runs (:func:`plan_run`): which stages are wanted
(``[run] stages``, default every stage the inputs and sections allow) and which stages they read
(:data:`rockmass.run_config.STAGES` order), every input file and every ``"@traces"`` /
``"@scanline"`` reference (:mod:`rockmass.run_config` states the rule) — a problem is bad input
(:class:`~rockmass.errors.InputError`, exit 2) naming the file, the field and what is expected.

Each stage then runs the single-stage subcommand's own compute-and-write function (``produce``
of :mod:`rockmass.extract_stage`, :mod:`rockmass.traces_stage`, ...) into ``DIR/<stage>/``, so a
stage folder holds exactly the files that subcommand writes into its ``--out``, plus ``stage.json``.

Reuse. A stage's hash is the SHA-256 of its config section(s) (resolved: defaults filled in), the
SHA-256 of every input file it reads, the hashes of the upstream stages it reads, and the rockmass
version. ``DIR/<stage>/stage.json`` records it and each output's SHA-256; when the hash matches and
every output recorded there has its SHA-256 (a truncated or edited output does not), the stage is
reused (not recomputed) and the log says ``reused <stage> (hash …)``. A changed
setting changes its stage's hash and so every downstream hash: exactly those stages rerun. The
hashes, and the config each stage's ``manifest.json`` records and hashes, write the run's own
outputs as ``<run>/<stage>/<file>`` and other paths relative to the config's folder
(:func:`rockmass.manifest.portable_paths`), so they do not depend on where DIR or the project is.

Atomicity. A stage writes into ``DIR/<stage>.partial/`` (every file atomically, ``stage.json``
last), which then replaces ``DIR/<stage>/``; a killed stage never looks finished, and the next run
removes what it left (``<stage>.partial``, ``<stage>.old``, temporary files; a link named like
them is removed, never written through). ``run.json`` is
written atomically after the stages, then ``report.html`` (:func:`rockmass.run_report
.write_run_report`), then ``manifest.json`` listing every file with its SHA-256.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import time
import types
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .errors import ConfigError, InputError, RunError, reading
from .outputs import PARTIAL_SUFFIX as _PARTIAL
from .outputs import remove_entry, remove_write_debris
from .run_config import REFERENCES, STAGES

__all__ = ["RUN_FILE", "STAGE_FILE", "RunPlan", "StagePlan", "execute", "plan_run", "stage_hash"]

STAGE_FILE = "stage.json"
RUN_FILE = "run.json"
_OLD = ".old"


@dataclass
class StagePlan:
    """One stage of a run: what it reads and how it is hashed (see the module docstring)."""

    name: str
    sections: dict[str, Any]          # config data that decides the stage (JSON-able)
    files: list[Path]                 # input files read (hashed)
    upstream: list[str]               # stages whose outputs it reads
    hash: str = ""


@dataclass
class RunPlan:
    """A validated run: the document with ``@`` references resolved, and the stages in order."""

    config_path: Path
    document: Any                     # RockmassConfig with @-references replaced by paths
    stages: list[StagePlan]
    trace_map: Path | None            # the run's trace map (extract's output or [run] traces)
    scanline: Path | None
    out_dir: Path
    config: dict = field(default_factory=dict)  # the document as written, [run] included (JSON)
    digests: dict = field(default_factory=dict)  # file digests of this run (manifest.digest_cache)


# ----------------------------------------------------------------------------------- planning --


def _problem(config_path, key: str, message: str) -> ConfigError:
    return ConfigError(str(config_path), [(key, message)])


def _resolve_refs(config_path, document, trace_map: Path | None, scanline: Path | None):
    """The document with every ``"@..."`` file reference replaced by an absolute path. Unknown
    references and references to data the run does not have are errors naming the field."""

    def resolve(value: str, key: str) -> str:
        if not value.startswith("@"):
            return value
        if value not in REFERENCES:
            raise _problem(config_path, key, f"unknown reference {value!r} (a run knows: "
                           + "; ".join(f"{k} = {v}" for k, v in REFERENCES.items()) + ")")
        target = trace_map if value == "@traces" else scanline
        if target is None:
            need = ("[run] photo or [run] traces" if value == "@traces" else "[run] scanline")
            raise _problem(config_path, key, f"{value} names {REFERENCES[value]}, but the config "
                           f"has no {need}")
        return str(Path(target).resolve())

    updates = {}
    dfn = document.dfn
    if dfn is not None and dfn.fit is not None:
        fit = dfn.fit
        scanlines = [resolve(v, f"dfn.fit.scanlines[{i}]") for i, v in enumerate(fit.scanlines)]
        faces = [f.model_copy(update={"file": resolve(f.file, f"dfn.fit.faces[{i}].file")})
                 for i, f in enumerate(fit.faces)]
        updates["dfn"] = dfn.model_copy(update={"fit": fit.model_copy(
            update={"scanlines": scanlines, "faces": faces})})
    blocks = document.blocks
    if blocks is not None and blocks.traces is not None:
        updates["blocks"] = blocks.model_copy(update={"traces": resolve(blocks.traces, "blocks.traces")})
    solve = document.solve
    if solve is not None and solve.blocks_file is not None and solve.blocks_file.startswith("@"):
        raise _problem(config_path, "solve.blocks_file", "takes a file, not a reference: leave it "
                       "out and the run solves its own blocks stage")
    return document.model_copy(update=updates)


def _check_file(config_path, key: str, path: Path | None) -> None:
    if path is not None and Path(path).is_dir():
        raise InputError(f"{config_path}: {key}: {path}: a folder, not a file (give the file "
                         "inside it)")
    if path is not None and not Path(path).is_file():
        raise InputError(f"{config_path}: {key}: {path}: no such file (paths are relative to the "
                         "config file)")


def _check_photo(path: Path) -> None:
    """The photo: within the pixel limit (from its header), an image Pillow can open, and its
    pixel data decodes to the end (a truncated JPEG passes ``verify``; JPEGs are decoded at 1/8
    scale, which reads the whole stream at a fraction of the cost; a PNG or TIFF is decoded whole,
    once more than extract will, within the pixel limit checked first)."""
    from PIL import Image, UnidentifiedImageError

    from .image_limits import check_image_pixels

    check_image_pixels(path, option=None)  # run has no --max-pixels: the environment variable
    try:
        with Image.open(path) as image:
            image.verify()
        with Image.open(path) as image:
            image.draft(image.mode, (1, 1))
            image.load()
    except (UnidentifiedImageError, SyntaxError) as exc:
        raise InputError(f"not a readable image (JPEG, PNG or TIFF expected): {exc}") from exc
    except OSError as exc:  # the decoder's: truncated or corrupt data
        raise InputError(f"the image could not be decoded (truncated or corrupt?): {exc}") from exc


def _read_traces(path: Path) -> None:
    """The trace map, read whole (GeoJSON or CSV)."""
    from .inputs import read_trace_file

    read_trace_file(path, quiet=True)  # its warnings come when the stage reads it


def _read_stage_traces(path: Path) -> None:
    """The ``run.traces`` map, read whole, within the trace limit of the traces stage."""
    from .budgets import check_traces
    from .inputs import read_trace_file

    trace_map = read_trace_file(path, quiet=True)  # its warnings come when the stage reads it
    check_traces(trace_map.n_traces, path)  # run has no --max-traces: the environment variable


def _read_scanline(path: Path) -> None:
    """The scanline survey, read whole."""
    from .dfn.scanline import read_scanline

    read_scanline(path)


def _history_reader(history) -> Callable[[Path], Any]:
    """The reader of a ``type = "csv"`` velocity history: the table, read whole."""
    return history.read


def _check_contents(config_path, files: list[tuple[str, Path, Callable[[Path], Any]]]) -> None:
    """Read what the stages will read before any runs (issue 18): each ``(field, path, reader)``;
    a problem is bad input naming the config, the field and the file (by its name only, nothing
    quoted from it). Returns nothing: the stages read the files again, whole."""
    for key, path, read in files:
        with reading(path, key, config=config_path):
            read(path)


def _check_excavation_names(config_path, solve, region_names) -> None:
    """The excavation stages ``[solve]`` removes exist in the blocks it solves (by name or region
    number: ``region_names`` of the run's ``[blocks]`` or of ``solve.blocks_file``), checked while
    planning: found by the solve stage, after the blocks were built, they cost every stage before
    it (issue 18)."""
    from types import SimpleNamespace

    model = SimpleNamespace(region_names=tuple(region_names))
    for i, stage in enumerate(solve.stages):
        try:
            stage.regions(model)
        except ValueError as exc:
            raise _problem(config_path, f"solve.stages[{i}].excavate", str(exc)) from exc


def plan_run(config_path, out_dir, document=None) -> RunPlan:
    """Validate a run config and plan its stages; raise before anything runs.

    Parameters
    ----------
    config_path : path-like
        The TOML file (:class:`rockmass.config.RockmassConfig` with a ``[run]`` section).
    out_dir : path-like
        The run's output folder.
    document : RockmassConfig, optional
        The loaded document (loaded from ``config_path`` if not given).

    Returns
    -------
    RunPlan

    Raises
    ------
    ConfigError, InputError
        Exit code 2: the message names the file, the field and what is expected.
    """
    from . import __version__
    from .config import load_config
    from .manifest import digest_cache

    config_path = Path(config_path)
    out_dir = Path(out_dir)
    if document is None:
        document = load_config(config_path)
    run = document.run
    if run is None:
        raise _problem(config_path, "run", "required section is missing (rockmass run reads [run]: "
                       "photo / traces / scanline and optionally stages)")
    if run.photo is not None and run.traces is not None:
        raise _problem(config_path, "run.traces", "give either photo or traces, not both (the run "
                       "has one trace map)")
    photo, traces_file, scanline = (run.path(k, config_path) for k in ("photo", "traces", "scanline"))
    for key, path in (("run.photo", photo), ("run.traces", traces_file), ("run.scanline", scanline)):
        _check_file(config_path, key, path)
    contents = [(key, path, read) for key, path, read in (
        ("run.photo", photo, _check_photo), ("run.traces", traces_file, _read_stage_traces),
        ("run.scanline", scanline, _read_scanline)) if path is not None]
    trace_map = (out_dir.resolve() / "extract" / "traces.geojson" if photo is not None
                 else traces_file)
    as_written = {**document.model_dump(mode="json"), "run": run.model_dump(mode="json")}
    document = _resolve_refs(config_path, document, trace_map, scanline)

    why_not = _unavailable_stages(config_path, document, photo, trace_map, scanline)
    upstream = _upstream_stages(config_path, document, photo, trace_map)
    needed = _needed_stages(config_path, run, why_not, upstream)
    stage_files, blocks_file = _stage_input_files(config_path, document, needed, contents,
                                                   photo, traces_file, scanline, trace_map)

    from .traces_stage import AREA_CHOICES

    area = run.area_value(config_path)
    if "traces" in needed and area is not None and area not in AREA_CHOICES:  # a file
        _check_file(config_path, "run.area", Path(area))
        stage_files["traces"].append(Path(area))
    read = {p for name in needed for p in stage_files[name]}  # files only unneeded stages read
    _check_contents(config_path, [c for c in contents if c[1] in read])  # are not read
    if blocks_file is not None:  # the model solved, and the excavations [solve] names in it
        from .solve_stage import read_blocks_file

        with reading(blocks_file, "solve.blocks_file", config=config_path):
            region_names = read_blocks_file(blocks_file).region_names
        _check_excavation_names(config_path, document.solve, region_names)
    if "traces" in needed:
        _check_area(config_path, traces_file if photo is None else None, area)

    sections = _stage_sections(document, run)
    plans: list[StagePlan] = []
    hashes: dict[str, str] = {}
    digests: dict = {}
    with digest_cache(digests):
        for name in STAGES:
            if name not in needed:
                continue
            sp = StagePlan(name, sections[name], stage_files[name], upstream[name])
            sp.hash = stage_hash(sp, {u: hashes[u] for u in sp.upstream}, __version__, config_path,
                                 out_dir)
            hashes[name] = sp.hash
            plans.append(sp)
    return RunPlan(config_path=config_path, document=document, stages=plans, trace_map=trace_map,
                   scanline=scanline, out_dir=out_dir, config=as_written, digests=digests)


def _unavailable_stages(config_path, document, photo, trace_map, scanline) -> dict[str, str]:
    """Stages the config cannot run, each with what it lacks (a photo, a trace map, a scanline, a
    section, blocks); both ``solve.blocks_file`` and a ``[blocks]`` section is an error."""
    why_not: dict[str, str] = {}
    if photo is None:
        why_not["extract"] = "needs [run] photo"
    if trace_map is None:
        why_not["traces"] = why_not["boxcount"] = "needs a trace map: give [run] photo or [run] traces"
    if scanline is None:
        why_not["scanline"] = "needs [run] scanline (a scanline survey CSV)"
    if document.dfn is None:
        why_not["dfn"] = "needs a [dfn] section"
    if document.blocks is None:
        why_not["blocks"] = "needs a [blocks] section"
    if document.solve is None:
        why_not["solve"] = "needs a [solve] section"
    elif document.blocks is None and document.solve.blocks_file is None:
        why_not["solve"] = "needs blocks: a [blocks] section (the run's blocks stage) or solve.blocks_file"
    elif document.blocks is not None and document.solve.blocks_file is not None:
        raise _problem(config_path, "solve.blocks_file", "give either blocks_file or a [blocks] "
                       "section, not both")
    return why_not


def _upstream_stages(config_path, document, photo, trace_map) -> dict[str, list[str]]:
    """For each stage, the stages whose outputs it reads (the extracted traces, the DFN section,
    the blocks)."""
    via_extract = ["extract"] if photo is not None else []
    upstream: dict[str, list[str]] = {s: [] for s in STAGES}
    upstream["traces"] = upstream["boxcount"] = list(via_extract)
    dfn_refs, blocks_refs = _references(document, trace_map)
    if "@traces" in dfn_refs:
        upstream["dfn"] += via_extract
    if document.blocks is not None:
        if "@traces" in blocks_refs:
            upstream["blocks"] += via_extract
        if document.blocks.dfn_section is not None:
            upstream["blocks"].append("dfn")
            _check_dfn_section(config_path, document)
    if document.solve is not None and document.solve.blocks_file is None:
        upstream["solve"].append("blocks")
    return upstream


def _needed_stages(config_path, run, why_not: dict, upstream: dict) -> set[str]:
    """The stages to run: those asked for (``[run] stages``, else every stage the config can
    run) and, recursively, the stages they read; asking for one that cannot run names why."""
    requested = list(run.stages) if run.stages else [s for s in STAGES if s not in why_not]
    if not requested:
        raise _problem(config_path, "run", "nothing to run: give [run] photo, traces or scanline, or "
                       "a [dfn], [blocks] or [solve] section")
    needed: set[str] = set()

    def need(name: str, wanted_by: str | None) -> None:
        if name in why_not:
            who = "[run] stages" if wanted_by is None else f"stage {wanted_by!r} (it reads {name!r})"
            key = "run.stages" if run.stages else "run"
            raise _problem(config_path, key, f"{who}: stage {name!r} {why_not[name]}")
        needed.add(name)
        for up in upstream[name]:
            need(up, name)

    for name in requested:
        need(name, None)
    return needed


def _stage_input_files(config_path, document, needed: set, contents: list, photo, traces_file,
                       scanline, trace_map) -> tuple[dict, Path | None]:
    """The input files of every needed stage (each checked to exist; those to read before the
    run appended to ``contents``), and the blocks file the solve stage reads, if any."""
    stage_files: dict[str, list[Path]] = {s: [] for s in STAGES}
    if photo is not None:
        stage_files["extract"].append(photo)
    if traces_file is not None:
        stage_files["traces"].append(traces_file)
        stage_files["boxcount"].append(traces_file)
    if scanline is not None:
        stage_files["scanline"].append(scanline)
    if "dfn" in needed and document.dfn.fit is not None:
        fit = document.dfn.fit
        for i, name in enumerate(fit.scanlines):
            p = fit.path(name, config_path)
            _check_file(config_path, f"dfn.fit.scanlines[{i}]", p)
            contents.append((f"dfn.fit.scanlines[{i}]", p, _read_scanline))
            stage_files["dfn"].append(p)
        for i, face in enumerate(fit.faces):
            p = fit.path(face.file, config_path)
            if p != trace_map or photo is None:
                _check_file(config_path, f"dfn.fit.faces[{i}].file", p)
                if p != traces_file:
                    contents.append((f"dfn.fit.faces[{i}].file", p, _read_traces))
                stage_files["dfn"].append(p)
            # scanline TOML beside a CSV is read by read_scanline: hash it too
        for p in list(stage_files["dfn"]):
            toml = p.with_suffix(".toml")
            if toml.is_file():
                stage_files["dfn"].append(toml)
    if scanline is not None and scanline.with_suffix(".toml").is_file():
        stage_files["scanline"].append(scanline.with_suffix(".toml"))
    if "blocks" in needed:
        p = document.blocks.traces_path(config_path)
        if p is not None and (p != trace_map or photo is None):
            _check_file(config_path, "blocks.traces", p)
            if p != traces_file:
                contents.append(("blocks.traces", p, _read_traces))
            stage_files["blocks"].append(p)
    blocks_file = None
    if "solve" in needed:
        cfg = document.solve
        blocks_file = cfg.blocks_path(config_path)
        if blocks_file is not None:
            _check_file(config_path, "solve.blocks_file", blocks_file)
            stage_files["solve"].append(blocks_file)
        elif document.blocks is not None:
            _check_excavation_names(config_path, cfg,
                                    ("rock", *(e.name for e in document.blocks.excavations)))
        base = config_path.parent
        for i, v in enumerate(cfg.velocity_inputs):
            if v.history.type == "csv":
                key = f"solve.velocity_inputs[{i}].history.file"
                hp = v.history.path(base)
                _check_file(config_path, key, hp)
                contents.append((key, hp, _history_reader(v.history)))
                stage_files["solve"].append(hp)
    return stage_files, blocks_file


def _stage_sections(document, run) -> dict[str, dict]:
    """The config sections each stage's hash covers."""
    return {
        "extract": {"imaging": _dump(document.imaging), "run.trace_sets": run.trace_sets},
        # run.area only when given: the hash of a run without it is what it was before issue 19
        "traces": {"run.trace_sets": run.trace_sets, **({"run.area": run.area} if run.area else {})},
        "boxcount": {"fractal": _dump(document.fractal)},
        "scanline": {"run.scanline_sets": run.scanline_sets},
        "dfn": {"dfn": _dump(document.dfn)},
        "blocks": {"blocks": _dump(document.blocks),
                   "dfn.sections": (_dump(document.dfn)["sections"]
                                    if document.blocks is not None and document.blocks.dfn_section
                                    is not None else None)},
        "solve": {"solve": _dump(document.solve)},
    }


def _check_area(config_path, traces_file: Path | None, area: str | None) -> None:
    """The traces stage has an area (issue 19): ``run.area`` (a polygon file in the map's CRS,
    or "bbox" / "hull") or the window polygon of the ``[run] traces`` file (``traces_file``; None
    for a photo's traces, which always have one). Bad input names ``run.area``."""
    from .traces_stage import AREA_CHOICES, area_window

    if traces_file is None and (area is None or area in AREA_CHOICES):
        return
    trace_map = None
    if traces_file is not None:
        from .inputs import read_trace_file

        with reading(traces_file, "run.traces", config=config_path):
            trace_map = read_trace_file(traces_file, quiet=True)
    if trace_map is None or trace_map.n_traces == 0:
        if area is not None and area not in AREA_CHOICES:  # a photo's traces: check the polygon alone
            from .inputs import read_polygon_file

            with reading(area, "run.area", config=config_path):
                read_polygon_file(area, "run.area")
        return
    try:
        area_window(trace_map, area, traces_file, "run.area")
    except InputError as exc:
        raise _problem(config_path, "run.area", str(exc)) from None


def _references(run_document, trace_map) -> tuple[set[str], set[str]]:
    """Which stage sections read the run's trace map (after resolution: the path equals it)."""
    dfn_refs, blocks_refs = set(), set()
    if trace_map is None:
        return dfn_refs, blocks_refs
    target = str(Path(trace_map).resolve())
    dfn = run_document.dfn
    if dfn is not None and dfn.fit is not None and any(f.file == target for f in dfn.fit.faces):
        dfn_refs.add("@traces")
    blocks = run_document.blocks
    if blocks is not None and blocks.traces == target:
        blocks_refs.add("@traces")
    return dfn_refs, blocks_refs


def _check_dfn_section(config_path, document) -> None:
    choice = document.blocks.dfn_section
    dfn = document.dfn
    if dfn is None:
        raise _problem(config_path, "blocks.dfn_section", "needs the [dfn] section (a run cuts the "
                       "section from its own DFN realization)")
    names = [s.name for s in dfn.sections]
    if choice.section not in names:
        raise _problem(config_path, "blocks.dfn_section.section",
                       f"no [[dfn.sections]] entry named {choice.section!r} (names: {names})")
    if choice.realization >= dfn.realizations:
        raise _problem(config_path, "blocks.dfn_section.realization",
                       f"must be < dfn.realizations ({dfn.realizations}), got {choice.realization}")


def _dump(section) -> Any:
    return None if section is None else section.model_dump(mode="json")


def _file_digest(path: Path) -> str:
    from .manifest import file_sha256

    return file_sha256(path)[0]


def stage_hash(stage: StagePlan, upstream_hashes: dict[str, str], version: str, config_path,
               out_dir) -> str:
    """SHA-256 of the stage's sections, input-file contents, upstream hashes and rockmass version.

    File paths are hashed relative to the config's folder where they can be, so moving a project
    folder keeps its hashes; a run's own outputs (``@traces`` of a photo) enter through the upstream
    hash, not as files.
    """
    from .config import config_hash
    from .manifest import portable_paths

    base = Path(config_path).resolve().parent
    files = []
    for p in stage.files:
        rp = Path(p).resolve()
        shown = os.path.relpath(rp, base)
        files.append([shown, _file_digest(rp)])
    sections = portable_paths(stage.sections, base, Path(out_dir).resolve())
    doc = {"stage": stage.name, "sections": sections, "files": files,
           "upstream": upstream_hashes, "rockmass_version": version}
    return config_hash(doc)


# ---------------------------------------------------------------------------------- executing --


def _ns(plan: RunPlan, argv, **kwargs) -> types.SimpleNamespace:
    return types.SimpleNamespace(argv=list(argv), config=str(plan.config_path), json=False, **kwargs)


def _run_stage(plan: RunPlan, stage: StagePlan, folder: Path, argv) -> dict:
    """Run one stage into ``folder`` with its subcommand's compute-and-write function; return
    notes for the log (e.g. a solver run that stopped). Every stage takes its settings from the
    planned document (what its hash was computed from), never from the config file again."""
    source = _CONFIG_FILES.get(stage.name)
    path = plan.document.run.path(source, plan.config_path) if source else None
    if path is None:
        return _run_stage_from(plan, stage, folder, argv)
    with reading(path, f"run.{source}", config=plan.config_path):
        return _run_stage_from(plan, stage, folder, argv)


#: The ``[run]`` file each stage reads, if the config names it (errors name it by its name only).
_CONFIG_FILES = {"extract": "photo", "traces": "traces", "boxcount": "traces", "scanline": "scanline"}


def _run_stage_from(plan: RunPlan, stage: StagePlan, folder: Path, argv) -> dict:
    """The work of :func:`_run_stage`."""
    doc = plan.document
    run = doc.run
    notes: dict = {}
    if stage.name == "extract":
        from .extract_stage import produce

        produce(_ns(plan, argv, photo=str(run.path("photo", plan.config_path)), out=str(folder),
                    m_per_px=None, control_points=None, joint_width_px=None, joint_width_m=None,
                    face_dip_deg=None, face_dip_direction_deg=None, roi=None, roi_px=None, bright_lines=False,
                    n_sets=run.trace_sets, debug_images=False), folder, document=doc)
    elif stage.name == "traces":
        from .traces_stage import produce

        produce(_ns(plan, argv, file=str(plan.trace_map), area=run.area_value(plan.config_path),
                    area_option="run.area", n_sets=run.trace_sets, snap_tolerance_m=None,
                    out=str(folder)), folder)
    elif stage.name == "boxcount":
        from .boxcount_stage import produce

        produce(_ns(plan, argv, file=str(plan.trace_map), grid=None, method=None, range_px=None,
                    n_offsets=None, line_rule=None, window=None, mask="auto", threshold=None,
                    invert=None, skeletonize=None, out=str(folder)), folder, document=doc)
    elif stage.name == "scanline":
        from .scanline_stage import DEFAULT_SEED, produce

        produce(_ns(plan, argv, file=str(plan.scanline), n_sets=run.scanline_sets,
                    terzaghi_cap_deg=15.0, seed=DEFAULT_SEED, out=str(folder)), folder)
    elif stage.name == "dfn":
        from .dfn_stage import produce
        from .dfn_config import DFNDocument

        produce(_ns(plan, argv, seed=None, realizations=None, first=0, out=str(folder)), folder,
                document=DFNDocument(dfn=doc.dfn))
    elif stage.name == "blocks":
        from .blocks_stage import produce

        section = _dfn_section(plan) if doc.blocks.dfn_section is not None else None
        produce(_ns(plan, argv, out=str(folder)), folder, document=doc, section=section)
    elif stage.name == "solve":
        from .solve_stage import produce
        from .solver.result import FAILED_STATUSES

        model = None
        if doc.solve.blocks_file is None:
            model = _read_blocks(plan.out_dir / "blocks" / "blocks.json")
        result, _ = produce(_ns(plan, argv, out=str(folder)), folder, document=doc, model=model)
        if result.status in FAILED_STATUSES:
            notes["failed"] = f"the solver stopped ({result.status}): {result.diagnostic}"
    return notes


def _read_blocks(path: Path):
    from .blockgen import read_json

    try:
        return read_json(path)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise RunError(f"{path}: cannot read the blocks stage's model: {exc}") from exc


def _dfn_section(plan: RunPlan):
    """(TraceMap, window) of ``[blocks.dfn_section]``: its ``[[dfn.sections]]`` plane cut through
    the run's realization (``dfn/realization_NNNN/fractures.csv``)."""
    from .dfn.network_io import read_fractures_csv
    from .dfn.orientation import normal_from_dip
    from .dfn.sampling import sample_plane

    doc = plan.document
    choice = doc.blocks.dfn_section
    sec = next(s for s in doc.dfn.sections if s.name == choice.section)
    path = plan.out_dir / "dfn" / f"realization_{choice.realization:04d}" / "fractures.csv"
    try:
        network = read_fractures_csv(path, domain_m=doc.dfn.domain_m())
    except (OSError, ValueError) as exc:
        raise RunError(f"{path}: cannot read the dfn stage's realization: {exc}") from exc
    traces = sample_plane(network, sec.point_m, normal_from_dip(sec.dip_deg, sec.dip_direction_deg),
                          sec.window_uv_m)
    return traces, [tuple(p) for p in sec.window_uv_m]


def _outputs(folder: Path) -> list[str]:
    """Every file below ``folder`` except stage.json, relative, sorted (POSIX separators)."""
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")
                  if p.is_file() and p.name != STAGE_FILE)


def _digests(folder: Path, outputs: list[str]) -> dict[str, str]:
    """SHA-256 of each output (relative name -> hex digest), as recorded in stage.json."""
    from .manifest import file_sha256

    return {name: file_sha256(folder / name)[0] for name in outputs}


def _reusable(folder: Path, digest: str) -> list[str] | None:
    """The outputs recorded in ``folder/stage.json`` when its hash is ``digest`` and every output
    is there with the SHA-256 recorded (a truncated or edited output is recomputed, issue 18)."""
    if folder.is_symlink():  # a stage folder is the run's own: never one that points elsewhere
        return None
    try:
        record = json.loads((folder / STAGE_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    outputs, recorded = record.get("outputs"), record.get("sha256")
    if record.get("hash") != digest or not isinstance(outputs, list) \
            or not isinstance(recorded, dict) or set(recorded) != set(outputs):
        return None
    if not all((folder / name).is_file() and not (folder / name).is_symlink() for name in outputs):
        return None
    try:
        if _digests(folder, outputs) != recorded:
            return None
    except InputError:  # unreadable: recompute
        return None
    return outputs


def _clean_debris(out: Path) -> None:
    """Remove what a killed run left in ``out``: staging folders ``<stage>.partial``, a previous
    stage folder ``<stage>.old`` (put back if the stage folder itself is missing: a kill between the
    two renames of :func:`_replace_folder`), and temporary files of the atomic writers."""
    for name in STAGES:
        folder, old = out / name, out / (name + _OLD)
        remove_entry(out / (name + _PARTIAL))
        if old.is_dir() and not old.is_symlink() and not os.path.lexists(folder):
            os.replace(old, folder)
        remove_entry(old)
    remove_write_debris(out)


def _log(message: str) -> None:
    print(f"rockmass run: {message}", file=sys.stderr, flush=True)


def execute(plan: RunPlan, *, force: bool = False, argv=("rockmass", "run"),
            log: Callable[[str], None] = _log) -> dict:
    """Run (or reuse) every planned stage, then write run.json, report.html and manifest.json.

    Returns the ``run.json`` document. Raises :class:`RunError` (exit 1) after writing everything
    when the solver stopped (overlap, unstable); its outputs say why. Each file is hashed once per
    run (``plan.digests``), unless it changes meanwhile.
    """
    from .manifest import digest_cache

    with digest_cache(plan.digests):
        return _execute(plan, force, argv, log)


def _execute(plan: RunPlan, force: bool, argv, log: Callable[[str], None]) -> dict:
    """The work of :func:`execute`."""
    from . import __version__
    from .atomic import atomic_write_json
    from .config import config_hash
    from .manifest import portable_config_paths
    from .run_report import write_run_report

    t_start = time.perf_counter()
    out = plan.out_dir
    try:
        out.mkdir(parents=True, exist_ok=True)
        _clean_debris(out)
    except OSError as exc:
        raise RunError(f"{out}: cannot create the output folder: {exc.strerror or exc}") from exc
    records, failures = [], []
    for stage in plan.stages:
        folder = out / stage.name
        t0 = time.perf_counter()
        outputs = None if force else _reusable(folder, stage.hash)
        if outputs is not None:
            status = "reused"
            log(f"reused {stage.name} (hash {stage.hash[:12]})")
        else:
            status = "ran"
            log(f"running {stage.name} ...")
            partial = out / (stage.name + _PARTIAL)
            remove_entry(partial)  # a link is removed, never written through (issue 18)
            try:
                with portable_config_paths(plan.config_path.parent, out):  # hash without --out
                    notes = _run_stage(plan, stage, partial, argv)
            except BaseException:
                with contextlib.suppress(OSError):
                    remove_entry(partial)
                raise
            if notes.get("failed"):
                failures.append(f"{stage.name}: {notes['failed']}")
            outputs = _outputs(partial)
            wall = time.perf_counter() - t0
            atomic_write_json(partial / STAGE_FILE, {
                "stage": stage.name, "hash": stage.hash, "rockmass_version": __version__,
                "sections": stage.sections, "upstream": stage.upstream,
                "inputs": [str(p) for p in stage.files], "outputs": outputs,
                "sha256": _digests(partial, outputs), "wall_s": wall})
            _replace_folder(partial, folder)
            log(f"ran {stage.name} in {wall:.2f} s (hash {stage.hash[:12]})")
        records.append({"name": stage.name, "dir": stage.name, "status": status, "hash": stage.hash,
                        "wall_s": time.perf_counter() - t0, "outputs": outputs})
    document = {"config": str(plan.config_path), "config_hash": config_hash(plan.config),
                "rockmass_version": __version__, "stages": records,
                "total_wall_s": time.perf_counter() - t_start}
    atomic_write_json(out / RUN_FILE, document)
    others = other_stage_folders(plan)
    if others:
        log(f"kept {', '.join(others)} from an earlier run in {out} (not asked for by this run: "
            "not in its manifest or report; reused if asked for again unchanged)")
    write_run_report(out)
    _write_manifest(plan, document, argv, failures, others)
    if failures:
        raise RunError("; ".join(failures) + f" (every output is in {out})")
    return document


def other_stage_folders(plan: RunPlan) -> list[str]:
    """Stage folders in DIR that this run does not produce (left by earlier runs that asked for
    other stages). They are kept — a later run asking for them again reuses them by hash — but are
    not part of this run: not in manifest.json, run.json or report.html."""
    planned = {s.name for s in plan.stages}
    return [n for n in STAGES if n not in planned and (plan.out_dir / n / STAGE_FILE).is_file()]


def _replace_folder(partial: Path, folder: Path) -> None:
    """Put the finished ``partial`` folder in place of ``folder`` (the old one removed after)."""
    old = folder.with_name(folder.name + _OLD)
    remove_entry(old)
    if os.path.lexists(folder):
        os.replace(folder, old)
    os.replace(partial, folder)
    remove_entry(old)


def _write_manifest(plan: RunPlan, document: dict, argv, failures: list[str],
                    others: list[str]) -> None:
    """manifest.json: every file of this run (not the stage folders ``others`` of earlier runs)."""
    from .manifest import MANIFEST_NAME, file_sha256, write_manifest

    out = plan.out_dir
    files = []
    for p in sorted(out.rglob("*")):
        rel = p.relative_to(out).as_posix()
        top = rel.split("/")[0]
        if not p.is_file() or rel == MANIFEST_NAME or top.endswith((_PARTIAL, _OLD)) or top in others:
            continue
        sha, size = file_sha256(p)
        files.append({"path": rel, "sha256": sha, "bytes": size})
    inputs = [plan.config_path] + sorted({p for s in plan.stages for p in s.files}, key=str)
    write_manifest(
        out, command=list(argv), config=plan.config, inputs=inputs,
        timings_s={s["name"]: s["wall_s"] for s in document["stages"]} | {"total": document["total_wall_s"]},
        extra={"stages": [{k: s[k] for k in ("name", "status", "hash")} for s in document["stages"]],
               "files": files, "failures": failures})
