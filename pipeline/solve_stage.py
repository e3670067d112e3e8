"""The work of ``rockmass solve`` and of the ``solve`` stage of ``rockmass run``.

The DEM run of the ``[solve]`` section and its outputs: :func:`prepare` loads the config, the block
model and the solver settings; :func:`solve` runs the solver (:func:`rockmass.solver.run`);
:func:`build_outputs` makes every output in memory (the frames through :mod:`rockmass.solver.vtu`);
:func:`produce` does all three and writes the files into a folder, all of them or none, also when
the run stopped.

The command (:mod:`rockmass.solve_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import time
from pathlib import Path

from .errors import ConfigError, InputError, RunError, reading
from .outputs import csv_text, output_set

__all__ = ["read_blocks_file", "prepare", "solve", "build_outputs", "produce"]

#: names ``rockmass solve`` may write besides those of the new set, dropped with the old set
#: rather than kept as the user's: the frames of an earlier solve (``blocks_0000.vtu`` …; a
#: ParaView series must not mix two runs, issue 18) and outputs written only for some models
#: (``bolts.csv``). A new optional output belongs here.
_OWNED = (r"blocks_\d{4,}\.vtu", r"bolts\.csv", r"zones\.csv", r"contacts\.vtu")


def read_blocks_file(path):
    """The block model of ``solve.blocks_file`` (a ``blocks.json`` of ``rockmass blocks``), read
    and checked against the model's invariants; a file that is not one raises :class:`InputError`
    (callers read it within :func:`rockmass.errors.reading`, which names the config, the field and
    the file, and quotes nothing from it)."""
    from .blockgen import check_model, read_json

    try:
        model = read_json(path)
    except (KeyError, TypeError) as exc:
        raise InputError(f"not a valid blocks.json: {exc}") from exc
    invariants = check_model(model)
    if not invariants["ok"]:
        raise InputError(f"fails the block-model invariants {invariants}")
    return model


def prepare(config_path, document=None, model=None):
    """Load the config (unless ``document`` is given), the block model (unless ``model`` is given:
    the ``run`` command passes the model its blocks stage built) and the solver settings.

    Returns ``(document, model, settings, inputs, timings)``; ``inputs`` are the files read (for the
    manifest). Raises ``ConfigError`` / ``InputError`` (exit 2) naming the file and field.
    """
    import types

    from .config import load_config, required_section

    t0 = time.perf_counter()
    if document is None:
        document = load_config(config_path)
    cfg = required_section(document, "solve", config_path)
    inputs = [str(config_path)]
    path = cfg.blocks_path(config_path)
    if path is not None and document.blocks is not None:
        raise ConfigError(config_path, [("solve.blocks_file", "give either blocks_file or a "
                                                              "[blocks] section, not both")])
    t1 = time.perf_counter()
    if model is not None:
        source = {"blocks_model": "given"}
    elif path is not None:
        with reading(path, "solve.blocks_file", config=config_path):  # names it, quotes nothing
            model = read_blocks_file(path)
        inputs.append(str(path))
        source = {"blocks_file": str(path)}
    elif document.blocks is not None:
        from .blocks_stage import compute

        _, model, _, _ = compute(types.SimpleNamespace(config=config_path))
        traces = document.blocks.traces_path(config_path)
        if traces is not None:
            inputs.append(str(traces))
        source = {"blocks_section": True}
    else:
        raise ConfigError(config_path, [("solve.blocks_file", "required: a blocks.json written by "
                                                              "rockmass blocks (or a [blocks] "
                                                              "section in this file)")])
    t2 = time.perf_counter()
    settings = cfg.to_settings(model, config_path)
    base = Path(config_path).parent
    inputs += [str(v.history.path(base)) for v in cfg.velocity_inputs if v.history.type == "csv"]
    t3 = time.perf_counter()
    timings = {"load_s": t1 - t0, "blocks_s": t2 - t1, "settings_s": t3 - t2}
    return document, model, settings, {"files": inputs, "source": source}, timings


def solve(model, settings, config_path, progress=None):
    """:func:`rockmass.solver.run`; a ``ValueError`` (settings that do not fit the model: a selector
    choosing no block, a time step above the stable limit) becomes an ``InputError`` naming the file.
    ``progress(done, total, stage_name)`` is called while stepping (:func:`rockmass.solver.runner.run`)."""
    from .solver import run as solver_run

    try:
        return solver_run(model, settings, progress=progress)
    except ValueError as exc:
        raise InputError(f"{config_path}: solve: {exc}") from exc


def _monitor_summary(result, model, settings) -> dict:
    """Per monitor: its block, and displacement at the end of each stage and its change.

    A monitor whose block failed (kept moving in a static stage and was taken out,
    :class:`rockmass.solver.failure.FailedBlock`) has no displacement from that stage on: a fall
    is not a displacement of the rock mass. Its entry says so (``failed``: the stage, the
    mechanism, how far the block had moved and the simulated time when it was taken out) and has
    no ``final_*``
    values; the stages before keep theirs."""
    import numpy as np

    from .solver.selectors import block_at_point

    hist = result.history
    out = {}
    chosen = result.info.get("monitor_blocks", {})  # zoned models: the runner's piece
    for m in settings.monitors:
        block = chosen.get(m.name)
        if block is None:
            block = m.block if m.block is not None else block_at_point(model, m.point_xy_m)
        entry = {"block": int(block), "region": int(model.region[block]),
                 "centroid_xy_m": [float(v) for v in model.centroid_xy_m[block]], "stages": []}
        failure = _failure_of(result, int(block))
        if failure is not None:
            entry["failed"] = failure
        ux_all = hist.get(f"{m.name}_ux_m")
        if ux_all is not None and len(ux_all):
            uy_all = hist[f"{m.name}_uy_m"]
            stages = np.asarray(hist["stage"])
            prev = (0.0, 0.0)
            for s in result.stages:
                if failure is not None and s.name == failure["stage"]:
                    break
                rows = np.flatnonzero(stages == s.name)
                if not len(rows):
                    continue
                ux, uy = float(ux_all[rows[-1]]), float(uy_all[rows[-1]])
                mag = np.hypot(ux_all[rows], uy_all[rows])
                entry["stages"].append({
                    "stage": s.name, "ux_m": ux, "uy_m": uy, "displacement_m": float(np.hypot(ux, uy)),
                    "max_displacement_in_stage_m": float(mag.max()),
                    "change_ux_m": ux - prev[0], "change_uy_m": uy - prev[1],
                    "change_m": float(np.hypot(ux - prev[0], uy - prev[1]))})
                prev = (ux, uy)
            final = entry["stages"][-1] if entry["stages"] and failure is None else None
            if final is not None:
                entry["final_ux_m"], entry["final_uy_m"] = final["ux_m"], final["uy_m"]
                entry["final_displacement_m"] = final["displacement_m"]
        c = result.contacts or {}
        if len(c.get("block_a", ())):
            mine = (np.asarray(c["block_a"]) == block) | (np.asarray(c["block_b"]) == block)
            slip = np.abs(np.asarray(c["plastic_slip_m"])[mine])
            entry["contacts_at_end"] = int(mine.sum())
            entry["max_contact_plastic_slip_m"] = float(slip.max(initial=0.0))
        out[m.name] = entry
    return out


def _failure_of(result, block: int) -> dict | None:
    """Where ``block`` failed: the stage, mechanism and displacement when it was taken out, or None.

    With deformable blocks the result's blocks are pieces (rigid blocks and zones): a failure names
    one piece of the block that fell and a monitor follows another (the zone under its point), so
    both are compared by the block they belong to (``result.zones["parent_block"]``)."""
    import numpy as np

    parent = (np.asarray(result.zones["parent_block"]) if result.zones and "parent_block" in result.zones
              else None)

    def original(piece: int) -> int:
        return int(parent[piece]) if parent is not None else piece

    for stage in result.stages:
        for failed in stage.failed_blocks:
            if original(int(failed["block"])) == original(block):
                return {"stage": stage.name, "mechanism": failed["mechanism"],
                        "displacement_at_removal_m": float(failed["displacement_m"]),
                        "time_s": float(failed["time_s"])}
    return None




def build_outputs(model, settings, result, timings) -> dict:
    """Everything ``rockmass solve`` writes, in memory: name -> str (text) or meshio Mesh."""
    import numpy as np

    from .solver.deformable import zone_rows
    from .solver.vtu import contact_mesh, frame_mesh, pvd_text

    files: dict = {}
    frames, pvd = [], []
    for i, fr in enumerate(result.frames):
        name = f"blocks_{i:04d}.vtu"
        files[name] = frame_mesh(model, fr)
        frames.append({"file": name, "stage": fr.stage, "step": int(fr.step),
                       "time_s": float(fr.time_s)})
        pvd.append((float(fr.time_s), name))
    files["blocks.pvd"] = pvd_text(pvd)
    history = result.history or {"time_s": np.zeros(0), "stage": np.zeros(0, str)}
    files["history.csv"] = csv_text(history)
    be = result.block_energy
    per_block = {"block_id": np.arange(model.n_blocks), "region": model.region}
    if result.zones:  # the result's blocks are the pieces: say whose they are
        per_block["parent_block"] = result.zones["parent_block"]
    files["block_energy.csv"] = csv_text(per_block | {
        "volume_m3": be["volume_m3"], "mass_kg": be["mass_kg"],
        "peak_velocity_m_s": be["peak_velocity_m_s"],
        "peak_kinetic_energy_j": be["peak_kinetic_energy_j"]})
    if result.zones:  # docs/dem.md §16: stress, strain and plastic state per zone
        files["zones.csv"] = csv_text(zone_rows(result.zones))
    contacts = result.contacts or {}
    files["contacts.csv"] = csv_text(contacts) if contacts else "block_a,block_b\n"
    files["contacts.vtu"] = contact_mesh(contacts)  # the same slots for ParaView (solver/vtu.py)
    if result.bolts:  # docs/dem.md §15: per bolt node, axial force, yield, bond slip
        files["bolts.csv"] = csv_text(result.bolts)
    doc = result.to_json_dict()
    doc["monitors"] = _monitor_summary(result, model, settings)
    doc["model"] = {"blocks": int(model.n_blocks), "contacts": int(model.n_contacts),
                    "regions": list(model.region_names), "joint_sets": list(model.set_names)}
    doc["frames"] = frames
    doc["timings_s"] = dict(timings)
    files["result.json"] = doc
    return files


def produce(args, out_dir, document=None, model=None, progress=None):
    """Prepare (:func:`prepare`), solve and write every output into the folder ``out_dir``, also when
    the run stopped (its status is in result.json); return ``(result, result.json document)``.

    The work of ``rockmass solve`` (and of the ``solve`` stage of ``rockmass run``). Without a
    ``progress`` callback, a bar per DEM stage on a terminal (:func:`rockmass.progress.solver_bar`).
    """
    from contextlib import ExitStack

    from .atomic import atomic_path, atomic_write_json, atomic_write_text
    from .blockgen import write_json
    from .manifest import build_manifest
    from .progress import solver_bar
    from .solver.vtu import write_vtu

    document, model, settings, inputs, timings = prepare(args.config, document, model)
    t0 = time.perf_counter()
    with solver_bar() as bar:
        result = solve(model, settings, args.config, progress or bar)
    timings["solve_s"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    if result.pieces is not None:  # deformable blocks: the outputs index the model's pieces
        model = result.pieces
    files = build_outputs(model, settings, result, timings)
    timings["outputs_s"] = time.perf_counter() - t1
    doc = files["result.json"]
    doc["timings_s"] = dict(timings)
    names = list(files) + ["blocks.json", "manifest.json"]
    with output_set(out_dir, owns=_OWNED) as out, ExitStack() as stack:
        paths = {name: stack.enter_context(atomic_path(out / name)) for name in names}
        for name, content in files.items():
            if name == "result.json":
                try:
                    atomic_write_json(paths[name], content)
                except ValueError as exc:  # NaN would be a solver bug: say so, exit 1
                    raise RunError(f"{args.config}: the result holds a non-finite value ({exc}); "
                                   "this is a bug, please report it with this config") from exc
            elif isinstance(content, str):
                atomic_write_text(paths[name], content)
            else:
                write_vtu(content, paths[name])
        write_json(model, paths["blocks.json"])
        manifest = build_manifest(command=args.argv, config=document, inputs=inputs["files"],
                                  timings_s=timings,
                                  extra={"status": result.status, "diagnostic": result.diagnostic,
                                         "blocks_source": inputs["source"]})
        atomic_write_json(paths["manifest.json"], manifest)
    return result, doc


