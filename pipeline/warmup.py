"""``rockmass warmup``: compile the numba kernels once, so that the first real run is warm.

Every kernel is ``@njit(cache=True)`` (README, "Compiled kernels and numba's cache"): the first
process that calls one compiles it and writes it to numba's cache, and every later process reads it
from there. A fresh install therefore pays the compilation in its first ``rockmass run`` (about
20 CPU-s of the quickstart's 27 in session 24, ``benchmarks/bench_run.py``). ``rockmass warmup`` pays it up
front: it runs small built-in problems through the library's public stage functions, which call
the kernels with the types a real run calls them with (every call site passes C-contiguous
float64 / int64 arrays: one signature per kernel, two for the solver's ``advance``, rigid and with
deformable blocks), and so fills the cache a later run reads: after it, ``rockmass run
samples/quickstart.toml`` compiles nothing (tests/pipeline/test_warmup.py).

Parts (:data:`PARTS`; each prints one line with its time):

- ``extract``: :func:`rockmass.imaging.extract` on a small synthetic face
  (:func:`rockmass.imaging.synthetic_face`), then the statistics and box count of its traces, as
  the ``extract`` stage does (skeleton and box-counting kernels);
- ``dfn``: a two-set disk network (:func:`rockmass.dfn.generation.generate`; clipping kernels),
  its polygons clipped to the domain (the ``fractures.vtu`` export) and a section through it;
- ``boxcount``: :func:`rockmass.fractal.box_count` of the section's traces (raster and vector)
  and of a binary image;
- ``blocks``: :func:`rockmass.blockgen.build` from joint sets and from the section's traces;
- ``blocks3d`` (``--all``, since session 24): the network's cube cut into 3D blocks around a
  tunnel (:func:`rockmass.blockgen.blocks3d.cut_box`), its keyblocks and block shapes: the
  polyhedron kernels of the ``blocks3d`` command, whose first run otherwise compiles them (about
  12 CPU-s; the default parts take 20 s of CPU, so a run that never cuts 3D blocks does not pay
  for them);
- ``solve``: :func:`rockmass.solver.run` on a jointed square with a tunnel: a static stage, the
  excavation and a short dynamic stage (velocity input, quiet boundary, bolts);
- ``zones`` (``--all``): the same with its blocks deformable (zone kernels).

Nothing is written anywhere but numba's cache; the cache is the one every command uses
(:func:`rockmass.kernel_cache.ensure_writable_cache`, called by the command line before any
subcommand; worker processes inherit its ``NUMBA_CACHE_DIR``). With two or more cores the parts
run in two worker processes — the solver's in one, the others in the other — so the wall time
is about that of the solver's part; ``--workers 1`` runs them in this process.
"""

from __future__ import annotations

import argparse
import functools
import os
import time
from collections.abc import Callable

__all__ = ["PARTS", "add_parser", "groups", "run", "run_group", "run_part"]

#: The square (metres) the solver's and the blocks' problems are cut in.
_SIDE_M = 8.0


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``warmup`` subcommand."""
    p = subparsers.add_parser(
        "warmup", help="compile the numba kernels once (after installing), so the first run is warm",
        description="Compile the numba kernels a typical run needs into numba's cache by running "
                    "small built-in problems (extract, dfn, boxcount, blocks, solve; with --all also "
                    "deformable blocks and 3D blocks); writes "
                    "nothing else. Run it once after installing, or after an upgrade; in a shared "
                    "install, with the users' NUMBA_CACHE_DIR.")
    p.add_argument("--workers", type=_workers_arg, default=None, metavar="N",
                   help="worker processes (default 2 with two or more cores, else 1; 1 runs in "
                        "this process)")
    p.add_argument("--all", action="store_true", dest="all_parts",
                   help="also the deformable-block (zone) kernels, which only runs with "
                        "[[solve.deformable]] need, and the 3D block kernels of blocks3d")
    p.set_defaults(handler=run)
    return p


def _workers_arg(text: str) -> int:
    """``argparse`` type of ``--workers``: a positive number of processes."""
    from .budgets import positive_count_arg

    return positive_count_arg(text, "processes")


# ------------------------------------------------------------------------------------ problems --

def _square(side: float = _SIDE_M):
    """Counter-clockwise square [0, side]²."""
    import numpy as np

    return np.array([[0.0, 0.0], [side, 0.0], [side, side], [0.0, side]])


def _face():
    """A small synthetic face photograph (240 x 360 px at 0.02 m/px, "easy") with two sets."""
    from .imaging import JointSetSpec, synthetic_face

    sets = (JointSetSpec(50.0, 40.0, 2.0, 0.5, 0.6), JointSetSpec(150.0, 40.0, 2.0, 0.5, 0.6))
    return synthetic_face("easy", seed=0, shape_px=(240, 360), m_per_px=0.02, sets=sets)


@functools.cache
def _network():
    """A two-set disk network (Fisher orientations, power-law radii, P32 0.5 each) in a 10 m cube."""
    from .dfn.generation import FisherOrientation, FractureSetSpec, IntensityP32, generate
    from .dfn.sizes import PowerLawSize

    sets = [FractureSetSpec(orientation=FisherOrientation(dip_deg=dip, dip_direction_deg=ddir,
                                                          kappa=40.0),
                            size=PowerLawSize(r_min_m=1.0, r_max_m=8.0, alpha=2.5),
                            intensity=IntensityP32(value=0.5), name=name)
            for name, dip, ddir in (("A", 70.0, 30.0), ("B", 60.0, 200.0))]
    return generate(sets, [[0.0, 0.0, 0.0], [10.0, 10.0, 10.0]], seed=0)


@functools.cache
def _section():
    """The traces of :func:`_network` on the vertical plane y = 5 m, window [0, 8]² (u, v). Both
    are made once per process: the dfn, boxcount and blocks parts share them."""
    from .dfn.sampling import sample_plane

    return sample_plane(_network(), (9.0, 5.0, 1.0), (0.0, 1.0, 0.0), _square())


def _blocks(traces=None):
    """The square cut by two joint sets (or by ``traces``), with a 2 m tunnel (region 1) in it."""
    from .blockgen import JointSet, build, circle

    sets = () if traces is not None else (JointSet(35.0, 1.5, origin_xy_m=(4.0, 4.0), name="a"),
                                          JointSet(120.0, 2.0, origin_xy_m=(4.0, 4.0), name="b"))
    return build(_square(), sets, traces=traces, excavations=[circle((4.0, 4.0), 1.0, n_sides=12)])


def _jointed_tunnel(deformable: bool = False):
    """(model, settings): :func:`_blocks` from joint sets; stages: gravity, excavation (static, a
    few hundred steps each) and a 5 ms shake (dynamic: a velocity input at the bottom, a quiet top,
    a bolt). ``deformable``: the bottom blocks are meshed into zones."""
    from .solver import (Bolt, BoltProperties, Coulomb, Deformable, Elastic, Fix, Material, Monitor,
                         QuietBoundary, Settings, Sine, Stage, VelocityInput)

    model = _blocks()
    joint = Coulomb(kn_pa_m=10e9, ks_pa_m=5e9, friction_deg=30.0)
    intact = Coulomb(kn_pa_m=10e9, ks_pa_m=5e9, friction_deg=45.0, cohesion_pa=2e6, tension_pa=1e6)
    bolt = Bolt(start_xy_m=(4.0, 5.0), end_xy_m=(4.0, 7.0), stage="tunnel",
                properties=BoltProperties(bond_stiffness_n_m2=1e8, bond_strength_n_m=2e5,
                                           axial_stiffness_n=5e7))
    settings = Settings(
        joints={"default": joint, "glued": intact, "excavation": intact},
        stages=(Stage("gravity", max_steps=300), Stage("tunnel", excavate=(1,), max_steps=300),
                Stage("shake", kind="dynamic", duration_s=0.005, rayleigh_ratio=0.01,
                      rayleigh_frequency_hz=50.0, frames=0)),
        material=Material(density_kg_m3=2650.0, bulk_modulus_pa=20e9, shear_modulus_pa=12e9),
        fixes=(Fix("bottom", "y"), Fix("left", "x"), Fix("right", "x")),
        velocity_inputs=(VelocityInput("bottom", "x", Sine(amplitude=0.01, frequency_hz=20.0)),),
        quiet=QuietBoundary(sides=("top",)), monitors=(Monitor("crown", point_xy_m=(4.0, 5.2)),),
        bolts=(bolt,), density_scaling=True,
        deformable=(Deformable("bottom", Elastic(20e9, 12e9), 1.0),) if deformable else ())
    return model, settings


# --------------------------------------------------------------------------------------- parts --

def _part_extract() -> str:
    """Extract a synthetic face, then its traces' statistics and box count (the extract stage)."""
    from .dfn import trace_map_statistics
    from .fractal import box_count
    from .imaging import extract

    face = _face()
    result = extract(face.image, m_per_px=face.m_per_px, joint_width_px=3.0, face_dip_deg=90.0,
                     face_dip_direction_deg=0.0)
    traces = result.traces
    if traces.n_traces:
        trace_map_statistics(traces, length_unit=result.scale.units)
        box_count(traces)
    return f"{traces.n_traces} traces on a {face.image.shape[1]} x {face.image.shape[0]} px face"


def _part_dfn() -> str:
    """Generate a disk network, clip its polygons to the domain and cut a section."""
    from .dfn import clip_disk_polygons

    network = _network()
    clip_disk_polygons(network)
    section = _section()
    return f"{network.n_fractures} disks, {section.n_traces} section traces"


def _part_boxcount() -> str:
    """Box counts of section traces (raster with their window, vector) and of a binary image."""
    import numpy as np

    from .fractal import box_count

    traces = _section()
    box_count(traces)
    box_count(traces, method="vector")
    image = np.zeros((128, 128), dtype=np.uint8)
    image[64, :] = 255
    image[:, 40] = 255
    box_count(image, grid=128)
    return f"{traces.n_traces} traces, a 128 x 128 px image"


def _part_blocks() -> str:
    """Block models from joint sets and from a DFN section's traces."""
    sets = _blocks()
    traces = _blocks(_section())
    return f"{sets.n_blocks} blocks from sets, {traces.n_blocks} from traces"


def _part_blocks3d() -> str:
    """3D blocks: the disk network's 10 m cube cut by its disks and a tunnel, the keyblocks and the
    block shapes (the ``blocks3d`` command's polyhedron kernels)."""
    import numpy as np

    from .blockgen.block_shapes import block_shapes
    from .blockgen.blocks3d import cut_box, disk_planes
    from .blockgen.keyblocks import keyblocks
    from .blockgen.openings3d import Tunnel, horseshoe_section

    network = _network()
    box = np.array([[0.0, 0.0, 0.0], [10.0, 10.0, 10.0]])
    tunnel = Tunnel(horseshoe_section(3.0, 1.5), centre_m=(5.0, 0.0, 4.0), trend_deg=0.0)
    blocks = cut_box(box, disk_planes(network), tunnels=(tunnel,))
    found = keyblocks(blocks, {i: (30.0, 0.0) for i in range(len(network.radius_m))})
    block_shapes(blocks)
    return f"{blocks.n_blocks} blocks in a 10 m cube, {len(found)} on the tunnel"


def _part_solve(deformable: bool = False) -> str:
    """Static, excavation and dynamic stages on the jointed tunnel."""
    from .solver import run as solve

    model, settings = _jointed_tunnel(deformable)
    result = solve(model, settings)
    steps = sum(stage.steps for stage in result.stages)
    return f"{model.n_blocks} blocks, {len(result.stages)} stages, {steps} steps"


def _part_zones() -> str:
    """The jointed tunnel with its bottom blocks deformable (zone kernels)."""
    return _part_solve(deformable=True)


#: name -> (function, group, only with ``--all``). A group's parts run one after another in one
#: process; the groups go to the workers in this order, the longest first. The zones part is in
#: the solver's group: it shares most of its kernels (``advance``'s callees), which a second
#: process would compile again at the same time.
PARTS: dict[str, tuple[Callable[[], str], str, bool]] = {
    "solve": (_part_solve, "solver", False),
    "zones": (_part_zones, "solver", True),
    "extract": (_part_extract, "field", False),
    "dfn": (_part_dfn, "field", False),
    "boxcount": (_part_boxcount, "field", False),
    "blocks": (_part_blocks, "field", False),
    "blocks3d": (_part_blocks3d, "field", True),
}


def groups(all_parts: bool) -> list[list[str]]:
    """The parts to run, by group, in the order of :data:`PARTS`."""
    out: dict[str, list[str]] = {}
    for name, (_, group, extra) in PARTS.items():
        if all_parts or not extra:
            out.setdefault(group, []).append(name)
    return list(out.values())


def run_part(name: str) -> tuple[str, float, float, str]:
    """Run one part; return (name, wall s, CPU s of this process, what it did)."""
    import warnings

    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # small problems: coarse-zone and similar warnings
        what = PARTS[name][0]()
    return name, time.perf_counter() - t0, time.process_time() - c0, what


def run_group(names: list[str]) -> list[tuple[str, float, float, str]]:
    """Run a group's parts one after another (in a worker process)."""
    return [run_part(name) for name in names]


# ------------------------------------------------------------------------------------- command --

def _default_workers() -> int:
    """2 when this process may use two or more cores, else 1."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return 2 if cores >= 2 else 1


def _print_part(name: str, wall: float, cpu: float, what: str) -> None:
    print(f"{name:<9} {wall:6.1f} s  ({cpu:5.1f} CPU-s)  {what}", flush=True)


def _run_in_workers(parts: list[list[str]], workers: int) -> None:
    """Each group in a worker process ('spawn': a clean interpreter that inherits the environment,
    hence ``NUMBA_CACHE_DIR``); a group's lines are printed as it finishes."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    with ProcessPoolExecutor(max_workers=workers,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(run_group, names) for names in parts]
        for future in as_completed(futures):
            for line in future.result():
                _print_part(*line)


def run(args) -> int:
    """Handler of ``rockmass warmup``."""
    from .kernel_cache import cache_location

    parts = groups(args.all_parts)
    workers = min(args.workers or _default_workers(), len(parts))
    t0 = time.perf_counter()
    if workers == 1:
        for names in parts:
            for name in names:
                _print_part(*run_part(name))
    else:
        _run_in_workers(parts, workers)
    n = sum(len(names) for names in parts)
    print(f"warmup: {n} parts in {time.perf_counter() - t0:.1f} s with {workers} "
          f"process{'es' if workers > 1 else ''}; numba cache: {cache_location()}")
    return 0
