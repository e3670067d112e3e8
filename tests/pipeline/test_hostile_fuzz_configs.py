"""Table-driven bad inputs for every config-driven subcommand (issue 18, "done when"): ``dfn``,
``blocks``, ``blocks3d``, ``solve``, ``run`` and ``study`` each get at least 20 bad config files,
and ``traces``, ``boxcount`` and ``scanline`` bad options and files beyond those of
test_hostile_fuzz.py.

Each row is a good base (a tiny config of the kind the samples hold: a 12 m domain, a few steps)
with one mistake a user could make: a wrong type, a negative, zero, NaN, infinite or huge number,
an angle out of range, an unknown or missing key, an empty table, a duplicate name, a name or a
file that does not exist, a folder or a 0-byte file where a file was meant, malformed TOML or
non-UTF-8 bytes.

Oracles (docs/design.md §4, issue 18): exit code 2; stderr names the config file and the key path
of the offending field (``site.toml: dfn.sets[0].orientation.kappa``; for a file named by the
config, the config, the key and the file) and says what was expected; no traceback; and nothing
half-written: a fresh ``--out`` is not created, and an ``--out`` holding the complete output set
of the good base is left byte for byte as it was, with no staging folder beside it.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

from rockmass.cli import main

from .test_cli_blocks3d import CONFIG as BLOCKS3D
from .test_cli_dfn import CONFIG as DFN
from .test_cli_solve import TINY as SOLVE_TINY
from .test_hostile_fuzz import SCANLINE
from .test_hostile_inputs_2 import BLOCKS, SLIPS, WINDOW
from .test_hostile_outputs import _listing

# ------------------------------------------------------------------------------- good bases

DFN_BASE = DFN.replace("realizations = 3", "realizations = 1")
SOLVE_BASE = (SOLVE_TINY.format(kn="1e9", ks="5e8").replace("max_steps = 3000", "max_steps = 20")
              .replace("duration_s = 0.12", "duration_s = 0.002"))
STUDY_BASE = BLOCKS + """
[study]
realizations = 1
seed = 7
[study.grid]
blocks.two_sets.theta_deg = [60.0]
"""
RUN_BASE = """[run]
traces = "map.geojson"
stages = ["boxcount"]

[fractal]
grid = 64
n_offsets = 1
"""


def _trace_map(window: bool = True) -> str:
    """The three traces of test_hostile_inputs_2.py in a 10 m window (``window``: with it)."""
    features = [{"type": "Feature", "properties": {"id": n},
                 "geometry": {"type": "LineString", "coordinates": xy}} for n, xy in SLIPS]
    return json.dumps({"type": "FeatureCollection", "features": features + [WINDOW] * window})


#: subcommand -> (good base config, extra arguments)
BASES = {"dfn": (DFN_BASE, []), "blocks": (BLOCKS, []), "blocks3d": (BLOCKS3D, []),
         "solve": (SOLVE_BASE, []), "run": (RUN_BASE, []),
         "study": (STUDY_BASE, ["--workers", "1"])}

# ------------------------------------------------------------------------------ the tables
#
# A row is name -> Bad(make, field, expected): ``make(base, folder)`` writes the bad config into
# ``folder`` (and any file it names) and returns its path; the message must hold
# "<config>: <field>" and ``expected`` (what was wanted).


@dataclass(frozen=True)
class Bad:
    make: Callable[[str, Path], Path]
    field: str
    expected: str


def _write(folder: Path, data: str | bytes, name: str = "site.toml") -> Path:
    path = folder / name
    if isinstance(data, str):
        data = data.encode()
    path.write_bytes(data)
    return path


def edit(old: str, new: str, field: str, expected: str, *, files: dict | None = None) -> Bad:
    """The base with ``old`` (which it must hold) replaced by ``new``; ``files``: name -> bytes
    written beside the config (or None: a folder of that name)."""
    def make(base: str, folder: Path) -> Path:
        assert old in base, f"the base has no {old!r}"
        for name, data in (files or {}).items():
            if data is None:
                (folder / name).mkdir()
            else:
                _write(folder, data, name)
        return _write(folder, base.replace(old, new, 1))
    return Bad(make, field, expected)


FOLDER, MISSING = "a folder", "no file"


def whole(data: bytes | str, field: str, expected: str, name: str = "site.toml") -> Bad:
    """A config file of these bytes, or a folder of its name (FOLDER), or no file (MISSING)."""
    def make(base: str, folder: Path) -> Path:
        if data == FOLDER:
            (folder / name).mkdir()
        elif data != MISSING:
            _write(folder, data, name)
        return folder / name
    return Bad(make, field, expected)


def _common(section: str) -> dict[str, Bad]:
    """The file-level mistakes every config command is given."""
    return {
        "empty-file": whole(b"", section, "required"),
        "malformed-toml": whole(f"[{section}\nseed = 1\n".encode(), "<file>", "invalid TOML"),
        "non-utf8": whole(f"[{section}]\n# caf\xe9\n".encode("latin-1"), "<file>", "not UTF-8"),
        "folder": whole(FOLDER, "<file>", "cannot read"),
        "missing": whole(MISSING, "<file>", "No such file"),
        "nul-bytes": whole(f"[{section}]\x00\n".encode(), "<file>", "invalid TOML"),
        "unknown-section": edit(f"[{section}]", f"[{section}s]\n[{section}]", f"{section}s",
                                "unknown key"),
    }


SECTION = """
[[dfn.sections]]
name = "face"
point_m = [6.0, 5.0, 4.0]
dip_deg = 90.0
dip_direction_deg = 0.0
window_uv_m = [[-4.0, -3.0], [4.0, -3.0], [4.0, 3.0], [-4.0, 3.0]]
"""

DFN_CASES = {
    **_common("dfn"),
    "seed-string": edit("seed = 5", 'seed = "five"', "dfn.seed", "must be an integer"),
    "seed-negative": edit("seed = 5", "seed = -5", "dfn.seed", "must be >= 0"),
    "realizations-zero": edit("realizations = 1", "realizations = 0", "dfn.realizations",
                              "must be >= 1"),
    "realizations-huge": edit("realizations = 1", "realizations = 1000000000",
                              "dfn.realizations", "must be <= 10000"),
    "domain-inverted": edit("max_m = [12, 10, 8]", "max_m = [-12, 10, 8]", "dfn.domain",
                            "must be > min_m"),
    "domain-nan": edit("max_m = [12, 10, 8]", "max_m = [nan, 10, 8]", "dfn.domain.max_m",
                       "must be a finite number"),
    "domain-inf": edit("max_m = [12, 10, 8]", "max_m = [inf, 10, 8]", "dfn.domain.max_m",
                       "must be a finite number"),
    "domain-2d": edit("max_m = [12, 10, 8]", "max_m = [12, 10]", "dfn.domain.max_m",
                      "exactly 3 items"),
    "domain-empty-table": edit("min_m = [0, 0, 0]\nmax_m = [12, 10, 8]\n", "", "dfn.domain",
                               "required key is missing"),
    "kappa-negative": edit("kappa = 20", "kappa = -3", "dfn.sets[0].orientation.kappa",
                           "must be >= 0"),
    "dip-120": edit("dip_deg = 50", "dip_deg = 120", "dfn.sets[0].orientation.dip_deg",
                    "must be <= 90"),
    "dip-direction-400": edit("dip_direction_deg = 270", "dip_direction_deg = 400",
                              "dfn.sets[0].orientation.dip_direction_deg", "must be <= 360"),
    "r-min-above-r-max": edit("r_min_m = 0.5", "r_min_m = 5.0", "dfn.sets[0].size",
                              "must be < r_max_m"),
    "radius-zero": edit("radius_m = 1.0", "radius_m = 0.0", "dfn.sets[1].size.radius_m",
                        "must be > 0"),
    "unknown-measure": edit('measure = "P32"', 'measure = "P33"', "dfn.sets[0].intensity",
                            "expected tags: 'P32', 'P10', 'P21'"),
    "intensity-negative": edit("value = 0.5", "value = -0.5", "dfn.sets[0].intensity",
                               "must be > 0"),
    "unknown-distribution": edit('distribution = "uniform"', 'distribution = "gaussian"',
                                 "dfn.sets[1].orientation",
                                     "expected tags: 'fisher', 'uniform', 'bootstrap'"),
    "unknown-key": edit("n_vertices = 8", "n_vertice = 8", "dfn.sets[1].n_vertice",
                        "unknown key (allowed: "),
    "two-vertices": edit("n_vertices = 8", "n_vertices = 2", "dfn.sets[1].n_vertices",
                         "must be >= 3"),
    # was accepted (exit 0): [blocks.dfn_section] picks a section by name
    "duplicate-section-names": edit("n_vertices = 8\n", "n_vertices = 8\n" + SECTION + SECTION,
                                    "dfn.sections", "names must be unique"),
    "missing-intensity": edit('intensity = { measure = "P32", value = 0.5 }\n', "",
                              "dfn.sets[0].intensity", "required key is missing"),
    "value-string": edit("value = 0.5", 'value = "half"', "dfn.sets[0].intensity.value",
                         "must be a number"),
}

EXCAVATION = """[[blocks.excavations]]
shape = "circle"
name = "tunnel"
"""

BLOCKS_CASES = {
    **_common("blocks"),
    "width-zero": edit("width_m = 12.0", "width_m = 0.0", "blocks.domain.width_m", "must be > 0"),
    "width-negative": edit("width_m = 12.0", "width_m = -12.0", "blocks.domain.width_m",
                           "must be > 0"),
    "width-nan": edit("width_m = 12.0", "width_m = nan", "blocks.domain.width_m",
                      "must be a finite number"),
    "width-inf": edit("width_m = 12.0", "width_m = inf", "blocks.domain.width_m",
                      "must be a finite number"),
    "width-huge": edit("width_m = 12.0", "width_m = 1e300", "blocks.domain.width_m",
                       "must be <= 1000000"),
    "origin-string": edit("origin_xy_m = [-6.0, -6.0]", 'origin_xy_m = "centre"',
                          "blocks.domain.origin_xy_m", "must be an array"),
    "alpha-400": edit("alpha_deg = 30.0", "alpha_deg = 400.0", "blocks.two_sets.alpha_deg",
                      "must be < 180"),
    "theta-zero": edit("theta_deg = 60.0", "theta_deg = 0.0", "blocks.two_sets.theta_deg",
                       "must be > 0"),
    "spacing-negative": edit("spacing_m = [3.0, 4.0]", "spacing_m = [-3.0, 4.0]",
                             "blocks.two_sets.spacing_m", "must be > 0"),
    "spacing-one-value": edit("spacing_m = [3.0, 4.0]", "spacing_m = [3.0]",
                              "blocks.two_sets.spacing_m", "exactly 2 items"),
    # was "blocks.sets[0]: ...", a key the file does not have
    "spacing-above-domain": edit("spacing_m = [3.0, 4.0]", "spacing_m = [300.0, 400.0]",
                                 "blocks.two_sets.spacing_m", "produces no joints in the domain"),
    "unknown-key": edit("[blocks.domain]", "seeed = 1\n[blocks.domain]", "blocks.seeed",
                        "unknown key (allowed: "),
    "unknown-shape": edit('shape = "circle"', 'shape = "triangle"', "blocks.excavations[0]",
                          "expected tags: 'circle'"),
    "radius-negative": edit("radius_m = 2.0", "radius_m = -2.0",
                            "blocks.excavations[0].radius_m", "must be > 0"),
    "two-sides": edit("n_sides = 12", "n_sides = 2", "blocks.excavations[0].n_sides",
                      "must be >= 8"),
    "excavation-outside": edit("center_xy_m = [0.0, 0.0]", "center_xy_m = [100.0, 100.0]",
                               "blocks.excavations[0]", "lies wholly outside the domain"),
    "duplicate-excavation": edit(EXCAVATION, EXCAVATION.replace('"tunnel"', '"tunnel"\n'
                                 "center_xy_m = [3.0, 3.0]\nradius_m = 1.0\n" + EXCAVATION),
                                 "blocks.excavations", "names must be unique"),
    "missing-radius": edit("radius_m = 2.0\n", "", "blocks.excavations[0].radius_m",
                           "required key is missing"),
    "empty-two-sets": edit("alpha_deg = 30.0\ntheta_deg = 60.0\nspacing_m = [3.0, 4.0]\n", "",
                           "blocks.two_sets", "required key is missing"),
    "traces-missing": edit("[blocks.domain]", 'traces = "absent.geojson"\n[blocks.domain]',
                           "blocks.traces", "absent.geojson: cannot read"),
    "traces-folder": edit("[blocks.domain]", 'traces = "maps.geojson"\n[blocks.domain]',
                          "blocks.traces", "maps.geojson: cannot read",
                          files={"maps.geojson": None}),
    "traces-empty": edit("[blocks.domain]", 'traces = "empty.geojson"\n[blocks.domain]',
                         "blocks.traces", "empty.geojson: invalid JSON",
                         files={"empty.geojson": b""}),
}

BLOCKS3D_CASES = {
    **_common("blocks3d"),
    "box-inverted": edit("box_max_m = [4.0, 4.0, 4.0]", "box_max_m = [-4.0, 4.0, 4.0]",
                         "blocks3d.box_max_m", "must exceed box_min_m"),
    "box-nan": edit("box_max_m = [4.0, 4.0, 4.0]", "box_max_m = [4.0, nan, 4.0]",
                    "blocks3d.box_max_m[1]", "must be a finite number"),
    "box-2d": edit("box_max_m = [4.0, 4.0, 4.0]", "box_max_m = [4.0, 4.0]",
                   "blocks3d.box_max_m", "exactly 3 items"),
    "box-string": edit("box_min_m = [0.0, 0.0, 0.0]", 'box_min_m = "origin"',
                       "blocks3d.box_min_m", "must be an array"),
    "box-huge": edit("box_max_m = [4.0, 4.0, 4.0]", "box_max_m = [1e300, 4.0, 4.0]",
                     "blocks3d.box_max_m", "must be <= 10000000"),
    "dip-91": edit("dip_deg = 0.0", "dip_deg = 91.0", "blocks3d.sets[0].dip_deg", "must be <= 90"),
    "dip-direction-360.5": edit("dip_direction_deg = 0.0", "dip_direction_deg = 360.5",
                                "blocks3d.sets[0].dip_direction_deg", "must be < 360"),
    "spacing-zero": edit("spacing_m = 1.0", "spacing_m = 0.0", "blocks3d.sets[0].spacing_m",
                         "must be > 0"),
    "spacing-negative": edit("spacing_m = 1.0", "spacing_m = -1.0",
                             "blocks3d.sets[0].spacing_m", "must be > 0"),
    "spacing-inf": edit("spacing_m = 1.0", "spacing_m = inf", "blocks3d.sets[0].spacing_m",
                        "must be a finite number"),
    "spacing-bool": edit("spacing_m = 1.0", "spacing_m = true", "blocks3d.sets[0].spacing_m",
                         "must be a number, got true"),
    "spacing-tiny": edit("spacing_m = 1.0", "spacing_m = 1e-6", "blocks3d.sets[0].spacing_m",
                         "more than the limit of 16 GiB"),
    "origin-2d": edit("origin_m = [0.0, 0.0, 0.5]", "origin_m = [0.0, 0.5]",
                      "blocks3d.sets[0].origin_m", "exactly 3 items"),
    "unknown-key": edit("spacing_m = 1.0", "spacing_m = 1.0\npersistence = 0.5",
                        "blocks3d.sets[0].persistence", "unknown key (allowed: "),
    "missing-spacing": edit("spacing_m = 1.0\n", "", "blocks3d.sets[0].spacing_m",
                            "required key is missing"),
    "unknown-tunnel-shape": edit('shape = "rectangle"', 'shape = "oval"', "blocks3d.tunnels[0]",
                                 "must be one of \"circle\", \"horseshoe\", \"rectangle\""),
    "tunnel-width-zero": edit("width_m = 1.0", "width_m = 0.0", "blocks3d.tunnels[0].width_m",
                              "must be > 0"),
    "tunnel-height-negative": edit("height_m = 1.0", "height_m = -1.0",
                                   "blocks3d.tunnels[0].height_m", "must be > 0"),
    # was accepted (exit 0): a model without its opening
    "tunnel-outside": edit("centre_m = [2.0, 0.0, 1.5]", "centre_m = [200.0, 0.0, 1.5]",
                           "blocks3d.tunnels[0]", "lies wholly outside the box"),
    "empty-table": edit(BLOCKS3D.split("[[blocks3d.sets]]")[0], "[blocks3d]\n",
                        "blocks3d.box_min_m", "required key is missing"),
    "dfn-realization-without-dfn": edit("[blocks3d]\n", "[blocks3d]\ndfn_realization = 0\n",
                                        "blocks3d", "needs [[dfn.sets]]"),
}

SOLVE_CASES = {
    **_common("solve"),
    "density-zero": edit("density_kg_m3 = 2700.0", "density_kg_m3 = 0.0",
                         "solve.material.density_kg_m3", "must be > 0"),
    "density-nan": edit("density_kg_m3 = 2700.0", "density_kg_m3 = nan",
                        "solve.material.density_kg_m3", "must be a finite number"),
    "kn-negative": edit("kn_pa_m = 1e9", "kn_pa_m = -1e9", "solve.joints.default.kn_pa_m",
                        "must be > 0"),
    "friction-95": edit("friction_deg = 30.0", "friction_deg = 95.0",
                        "solve.joints.default.friction_deg", "must be < 90"),
    "unknown-model": edit('model = "coulomb"', 'model = "mohr"', "solve.joints.default",
                          "expected tags: 'coulomb', 'cy'"),
    "joints-of-no-set": edit("[solve.joints.v]", "[solve.joints.w]", "solve.joints.w",
                             "no contact has this label"),
    # was "site.toml: solve: selector 'middle': ...", naming no key path (as the two monitors)
    "fix-where-middle": edit('where = "bottom"', 'where = "middle"', "solve.fixes[0].where",
                             "expected one of ('left', 'right', 'bottom', 'top')"),
    "component-z": edit('component = "x"', 'component = "z"',
                        "solve.velocity_inputs[0].component", "must be one of \"x\", \"y\""),
    "history-kind": edit('type = "sine"', 'type = "square"', "solve.velocity_inputs[0].history",
                         "expected tags: 'sine'"),
    "frequency-negative": edit("frequency_hz = 20.0", "frequency_hz = -20.0",
                               "solve.velocity_inputs[0].history", "must be > 0"),
    # was "absent.csv: solve.velocity_inputs[0].history: ...", naming no config
    "history-csv-missing": edit('type = "sine", amplitude = 0.05, frequency_hz = 20.0, cycles = 2',
                                'type = "csv", file = "absent.csv"',
                                "solve.velocity_inputs[0].history.file", "absent.csv: cannot read"),
    # was "site.toml: solve: monitor 'top': ..."
    "monitor-far-outside": edit("point_xy_m = [0.6, 0.4]", "point_xy_m = [480.0, 0.4]",
                                "solve.monitors[0].point_xy_m", "outside the model domain"),
    "monitor-block-999": edit("block = 0", "block = 999", "solve.monitors[1].block",
                              "must be a block index in [0, 8)"),
    "duplicate-monitor": edit('name = "base"', 'name = "top"', "solve.monitors",
                              "names must be unique"),
    "max-steps-zero": edit("max_steps = 20", "max_steps = 0", "solve.stages[0].max_steps",
                           "must be >= 1"),
    "max-steps-string": edit("max_steps = 20", 'max_steps = "many"', "solve.stages[0].max_steps",
                             "must be an integer"),
    "stage-kind": edit('kind = "dynamic"', 'kind = "quasi"', "solve.stages[1].kind",
                       "must be one of \"static\", \"dynamic\""),
    "duration-negative": edit("duration_s = 0.002", "duration_s = -0.002",
                              "solve.stages[1].duration_s", "must be > 0"),
    "duplicate-stage": edit('name = "shake"', 'name = "gravity"', "solve.stages",
                            "names must be unique"),
    "unknown-excavation": edit("frames = 4", 'frames = 4\nexcavate = ["tunnel"]',
                               "solve.stages[1].excavate", "unknown excavation stage 'tunnel'"),
    "no-stages": edit(SOLVE_BASE[SOLVE_BASE.index("[[solve.stages]]"):], "", "solve.stages",
                      "required key is missing"),
    "no-blocks": edit(SOLVE_BASE[:SOLVE_BASE.index("[solve]")], "", "solve.blocks_file",
                      "a blocks.json written by rockmass blocks"),
}
_HEAD = SOLVE_BASE[:SOLVE_BASE.index("[solve]\n") + len("[solve]\n")]
for _name, _files in [("blocks-file-absent", {}), ("blocks-file-folder", {"blocks.json": None}),
                      ("blocks-file-empty", {"blocks.json": b""}),
                      ("blocks-file-not-blocks", {"blocks.json": b'{"format": "x"}'})]:
    SOLVE_CASES[_name] = edit(_HEAD, '[solve]\nblocks_file = "blocks.json"\n',
                              "solve.blocks_file", "blocks.json: ", files=_files)

MAP = _trace_map().encode()


def run_edit(old: str, new: str, field: str, expected: str, files: dict | None = None) -> Bad:
    """A run config edit; the good trace map is always beside it (``files`` add to it)."""
    return edit(old, new, field, expected, files={"map.geojson": MAP, **(files or {})})


RUN_CASES = {
    **_common("run"),
    "traces-missing": edit("[run]", "[run]", "run.traces",
                           "map.geojson: no such file"),  # no map.geojson beside it
    # was "map.geojson: no such file"
    "traces-folder": edit("[run]", "[run]", "run.traces", "map.geojson: a folder, not a file",
                          files={"map.geojson": None}),
    "traces-empty": edit("[run]", "[run]", "run.traces", "map.geojson: invalid JSON",
                         files={"map.geojson": b""}),
    "traces-binary": edit("[run]", "[run]", "run.traces", "map.geojson: not UTF-8",
                          files={"map.geojson": bytes(range(256))}),
    "traces-and-photo": run_edit("[run]", '[run]\nphoto = "face.png"', "run",
                                 "give either photo or traces, not both"),
    "photo-text": run_edit('traces = "map.geojson"', 'photo = "face.png"', "run.photo",
                           "face.png: not a readable image",
                           files={"face.png": b"not a photo\n"}),
    "photo-truncated-png": run_edit('traces = "map.geojson"', 'photo = "face.png"', "run.photo",
                                    "face.png: not a readable image",
                                    files={"face.png": b"\x89PNG\r\n\x1a\n\x00\x00"}),
    "scanline-missing": run_edit("[run]", '[run]\nscanline = "survey.csv"', "run.scanline",
                                 "survey.csv: no such file"),
    "scanline-broken": run_edit('stages = ["boxcount"]', 'stages = ["boxcount", "scanline"]\n'
                                'scanline = "survey.csv"', "run.scanline", "survey.csv: line 8",
                                files={"survey.csv": SCANLINE.replace("1.4904,61.52",
                                                                      "1.4904,steep").encode()}),
    "unknown-stage": run_edit('stages = ["boxcount"]', 'stages = ["boxcounting"]', "run.stages",
                              "must be one of \"extract\", \"traces\""),
    "stages-string": run_edit('stages = ["boxcount"]', 'stages = "boxcount"', "run.stages",
                              "must be an array"),
    "stages-empty": run_edit('stages = ["boxcount"]', "stages = []", "run.stages",
                             "at least 1 items"),
    "stages-duplicate": run_edit('stages = ["boxcount"]', 'stages = ["boxcount", "boxcount"]',
                                 "run.stages", "each stage at most once"),
    "stage-without-section": run_edit('stages = ["boxcount"]', 'stages = ["solve"]', "run.stages",
                                      "needs a [solve] section"),
    "trace-sets-zero": run_edit("[run]", "[run]\ntrace_sets = 0", "run.trace_sets", "must be >= 1"),
    "trace-sets-nine": run_edit("[run]", "[run]\ntrace_sets = 9", "run.trace_sets", "must be <= 5"),
    "area-missing": run_edit('stages = ["boxcount"]', 'stages = ["traces"]\n'
                             'area = "outline.geojson"', "run.area",
                             "outline.geojson: no such file"),
    "area-word": run_edit('stages = ["boxcount"]', 'stages = ["traces"]\narea = "hull2"',
                          "run.area", "hull2: no such file"),
    "unknown-key": run_edit("[run]", '[run]\nphotos = "face.png"', "run.photos",
                            "unknown key (allowed: "),
    "no-inputs": run_edit('traces = "map.geojson"\n', "", "run",
                          "needs a trace map: give [run] photo or [run] traces"),
    "grid-4": run_edit("grid = 64", "grid = 4", "fractal.grid", "must be >= 8"),
    "unknown-method": run_edit("n_offsets = 1", 'n_offsets = 1\nmethod = "exact"',
                               "fractal.method", "must be one of \"raster\", \"vector\""),
    "unknown-reference": run_edit("[fractal]", '[blocks]\ntraces = "@photo"\n'
                                  "[blocks.domain]\nwidth_m = 8.0\nheight_m = 8.0\n[fractal]",
                                  "blocks.traces", "unknown reference '@photo'"),
}

STUDY_CASES = {
    **_common("study"),
    "realizations-zero": edit("realizations = 1", "realizations = 0", "study.realizations",
                              "must be >= 1"),
    "realizations-huge": edit("realizations = 1", "realizations = 1000000000",
                              "study.realizations", "must be <= 10000"),
    "seed-negative": edit("seed = 7", "seed = -7", "study.seed", "must be >= 0"),
    "seed-float": edit("seed = 7", "seed = 7.5", "study.seed", "must be an integer"),
    "grid-no-field": edit("blocks.two_sets.theta_deg = [60.0]",
                          "blocks.two_sets.thetta_deg = [60.0]", "study.grid",
                          "unknown key (allowed: "),
    "grid-a-table": edit("blocks.two_sets.theta_deg = [60.0]", "blocks.two_sets = [60.0]",
                         "study.grid", "must be a table"),
    "grid-empty-list": edit("theta_deg = [60.0]", "theta_deg = []", "study.grid", "empty list"),
    "grid-not-a-list": edit("theta_deg = [60.0]", "theta_deg = 60.0", "study.grid",
                            "must be a list of values"),
    "grid-out-of-range": edit("theta_deg = [60.0]", "theta_deg = [60.0, 400.0]",
                              "study.grid.blocks.two_sets.theta_deg", "must be <= 90"),
    "grid-wrong-type": edit("theta_deg = [60.0]", 'theta_deg = ["steep"]',
                            "study.grid.blocks.two_sets.theta_deg", "must be a number"),
    "grid-nan": edit("theta_deg = [60.0]", "theta_deg = [nan]",
                     "study.grid.blocks.two_sets.theta_deg", "must be a finite number"),
    "case-empty-table": edit("[study.grid]\nblocks.two_sets.theta_deg = [60.0]\n",
                             "[[study.cases]]\n", "study.cases", "empty table"),
    # was "study.cases.blocks...", without the entry's index
    "case-unknown-field": edit("[study.grid]\nblocks.two_sets.theta_deg = [60.0]\n",
                               '[[study.cases]]\n"blocks.two_sets.thetta_deg" = 60.0\n',
                               "study.cases[0].blocks.two_sets.thetta_deg",
                               "unknown key (allowed: "),
    "colour-by-number": edit("seed = 7", "seed = 7\ncolour_by = 3", "study.colour_by",
                             "must be a string"),
    # was "blocks.sed: unknown key", as if the base config held it
    "seed-fields-no-field": edit("seed = 7", 'seed = 7\nseed_fields = ["blocks.sed"]',
                                 "study.seed_fields", "unknown key (allowed: "),
    "displacement-inner": edit("seed = 7", 'seed = 7\ndisplacement = "inner"',
                               "study.displacement", "must be one of \"boundary\", \"overall\""),
    "unknown-key": edit("seed = 7", "seed = 7\nworkers = 4", "study.workers",
                        "unknown key (allowed: "),
    "base-width-negative": edit("width_m = 12.0", "width_m = -12.0", "blocks.domain.width_m",
                                "must be > 0"),
    "no-study-table": edit(STUDY_BASE[STUDY_BASE.index("[study]"):], "", "study",
                           "required key is missing"),
    "grid-traces-missing": edit("theta_deg = [60.0]", 'theta_deg = [60.0]\n"blocks.traces" = '
                                '["absent.geojson"]', "blocks.traces",
                                "absent.geojson: no such file"),
    "grid-duplicate-values": edit("theta_deg = [60.0]", "theta_deg = [60.0, 60.0]", "study",
                                  "are the same config"),
}

TABLES = {"dfn": DFN_CASES, "blocks": BLOCKS_CASES, "blocks3d": BLOCKS3D_CASES,
          "solve": SOLVE_CASES, "run": RUN_CASES, "study": STUDY_CASES}

# ------------------------------------------------------------------------------- the oracle


def _tree(folder: Path) -> dict[str, bytes | None]:
    """relative path -> bytes of every file (None: a folder) below ``folder``: a staging folder
    left empty shows as well as a changed file."""
    return {p.relative_to(folder).as_posix(): None if p.is_dir() else p.read_bytes()
            for p in sorted(folder.rglob("*"))}


def _exit_code(args: list[str]) -> int:
    """:func:`main`'s exit code, also for a usage error (argparse exits with code 2)."""
    try:
        return main(args)
    except SystemExit as exc:
        return exc.code


def refused(tmp_path: Path, capsys, args: list[str], fragments: list[str],
            previous: Path | None) -> str:
    """Run ``args`` twice, into a fresh --out and into a copy of the complete set ``previous``:
    each exits 2 with every fragment on stderr and no traceback; the fresh --out is not created,
    the copy is left byte for byte as it was, and no staging folder is left beside either."""
    around = set(_listing(tmp_path))
    fresh = tmp_path / "fresh"
    code = _exit_code([*args, "--out", str(fresh)])
    err = capsys.readouterr().err
    assert code == 2, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    assert "Traceback" not in err
    assert not fresh.exists(), "a failing command created --out"
    if previous is not None:
        kept = tmp_path / "kept"
        shutil.copytree(previous, kept, symlinks=True)
        before = _tree(kept)
        assert _exit_code([*args, "--out", str(kept)]) == 2
        again = capsys.readouterr().err
        assert all(fragment in again for fragment in fragments), again
        assert _tree(kept) == before, "a failing command changed the previous output set"
        around.add("kept")
    assert set(_listing(tmp_path)) == around, "debris beside --out"
    return err


@pytest.fixture(autouse=True)
def sixteen_gib(monkeypatch):
    """The same memory limit on every machine (the budget rows quote it)."""
    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "16G")


@pytest.fixture(scope="module")
def good_set(tmp_path_factory):
    """command -> the complete output set of its good base (each made once, on first use)."""
    made: dict[str, Path] = {}

    def get(command: str) -> Path:
        if command not in made:
            folder = tmp_path_factory.mktemp(f"good-{command}")
            base, extra = BASES[command]
            (folder / "map.geojson").write_bytes(MAP)
            config = _write(folder, base)
            out = folder / "out"
            assert main([command, str(config), *extra, "--out", str(out)]) == 0
            made[command] = out
        return made[command]
    return get


def test_every_config_command_has_at_least_20_bad_inputs():
    assert {command: len(table) >= 20 for command, table in TABLES.items()} == \
        dict.fromkeys(TABLES, True)


@pytest.mark.parametrize("command, name", [(c, n) for c, table in TABLES.items() for n in table])
def test_a_bad_config_exits_2_naming_file_and_field_and_writes_nothing(tmp_path, capsys, good_set,
                                                                       command, name):
    base, extra = BASES[command]
    bad = TABLES[command][name]
    config = bad.make(base, tmp_path)
    refused(tmp_path, capsys, [command, str(config), *extra],
            [f"{config}: {bad.field}", bad.expected], good_set(command))


# ------------------------------------------- traces, boxcount, scanline: options and more files
#
# test_hostile_fuzz.py gives these commands 22 (traces, boxcount) and 12 (scanline) bad files and
# a missing file and a folder; the rows below add bad options, the files an option names, and
# more scanlines, with the previous-set oracle. A row: name -> (make, expected), ``make(folder)``
# returning (arguments, the offending file).

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
TRACES = SAMPLES / "face_traces.geojson"


def _scanline(text: str, name: str = "survey.csv"):
    def make(folder: Path):
        path = folder / name
        path.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
        return ["scanline", str(path)], path
    return make


def _with(command: str, *args: str, file: Path = TRACES, aside: dict | None = None,
          flag: bool = False):
    """``command`` on ``file`` with the options ``args`` ("{f}": the folder); ``aside``: name ->
    bytes written in the folder first (None: a subfolder). What the message must name: the first
    option value inside the folder, else ``file``; with ``flag``, the option itself (a bad value
    given on the command line is the option's fault, not a file's)."""
    def make(folder: Path):
        for name, data in (aside or {}).items():
            (folder / name).mkdir() if data is None else (folder / name).write_bytes(data)
        values = [a.format(f=folder) for a in args]
        named = next((Path(v) for v in values if v.startswith(str(folder))), file)
        return [command, str(file), *values], (args[0] if flag else named)
    return make


_SC = SCANLINE.replace("1.4904,61.52,200.35", "{row}")
_NOT_A_POLYGON = _trace_map(window=False).encode()

SCANLINE_SAMPLE = SAMPLES / "quickstart_scanline.csv"

FILE_CASES = {
    "scanline": {
        "dip-direction-text": (_scanline(_SC.format(row="1.4904,61.52,SW")), "expected a number"),
        "inf-distance": (_scanline(_SC.format(row="inf,61.52,200.35")),
                         "must be a finite number"),
        "negative-length": (_scanline(SCANLINE.replace("# length: 30.000000", "# length: -30")),
                            "length must be in metres, > 0"),
        "length-shorter-than-data": (
            _scanline(SCANLINE.replace("# length: 30.000000", "# length: 2")),
            "is outside the scanline [0, length = 2 m]"),
        "plunge-100": (_scanline(SCANLINE.replace("# plunge: 0.000000", "# plunge: 100")),
                       "plunge must be in degrees"),
        "nul-byte": (_scanline(_SC.format(row="1.4904,61.5\x002,200.35")),
                     "expected a number (degrees, 0-90)"),
        "binary": (_scanline(bytes(range(256)) * 8), "not UTF-8 text"),
        "comments-only": (_scanline("\n".join(SCANLINE.splitlines()[:6]) + "\n"),
                          "no column row (distance, dip, dip_direction"),
        "sets-zero": (_with("scanline", "--sets", "0", file=SCANLINE_SAMPLE, flag=True),
                      "must be >= 1 (number of joint sets)"),
        "terzaghi-cap-95": (_with("scanline", "--terzaghi-cap", "95", file=SCANLINE_SAMPLE,
                                  flag=True), "must be in (0, 90) degrees"),
    },
    "traces": {
        "sets-zero": (_with("traces", "--sets", "0"), "must be >= 1 (number of joint sets)"),
        "snap-negative": (_with("traces", "--snap-tolerance", "-1"),
                          "snap_tolerance_m must be >= 0"),
        "area-missing": (_with("traces", "--area", "{f}/outline.geojson"),
                         "cannot read the --area file"),
        "area-folder": (_with("traces", "--area", "{f}/outline.geojson",
                              aside={"outline.geojson": None}), "cannot read the --area file"),
        "area-not-a-polygon": (_with("traces", "--area", "{f}/outline.geojson",
                                     aside={"outline.geojson": _NOT_A_POLYGON}),
                               "holds no polygon"),
        "max-traces-zero": (_with("traces", "--max-traces", "0", flag=True),
                            "must be a positive number of traces"),
    },
    "boxcount": {
        "grid-4": (_with("boxcount", "--grid", "4", flag=True), "must be >= 8"),
        "range-inverted": (_with("boxcount", "--range", "40", "2", flag=True),
                           "must be [min, max] with min < max"),
        "offsets-zero": (_with("boxcount", "--offsets", "0", flag=True), "must be >= 1"),
        "window-inverted": (_with("boxcount", "--window", "10", "10", "0", "0"),
                            "with xmax > xmin and ymax > ymin"),
        "mask-missing": (_with("boxcount", "--mask", "{f}/mask.geojson"),
                         "cannot read the --mask file"),
        "mask-empty": (_with("boxcount", "--mask", "{f}/mask.geojson",
                             aside={"mask.geojson": b""}), "invalid JSON"),
        "config-grid-string": (_with("boxcount", "--config", "{f}/site.toml",
                                     aside={"site.toml": b'[fractal]\ngrid = "big"\n'}),
                               "fractal.grid: must be an integer"),
    },
}


def test_scanline_has_at_least_20_bad_inputs_with_test_hostile_fuzz():
    from .test_hostile_fuzz import SCANLINE_FILES

    assert len(SCANLINE_FILES) + 2 + len(FILE_CASES["scanline"]) >= 20  # + a missing file, a folder


@pytest.mark.parametrize("command, name", [(c, n) for c,
    table in FILE_CASES.items() for n in table])
def test_a_bad_option_or_file_exits_2_naming_it_and_writes_nothing(tmp_path, capsys, good_files,
                                                                   command, name):
    make, expected = FILE_CASES[command][name]
    args, named = make(tmp_path)
    refused(tmp_path, capsys, args, [f"{named}: " if isinstance(named, Path) else named, expected],
            good_files(command))


@pytest.fixture(scope="module")
def good_files(tmp_path_factory):
    """command -> the complete output set of the command on its sample file (made once)."""
    made: dict[str, Path] = {}
    inputs = {"traces": TRACES, "boxcount": TRACES, "scanline": SCANLINE_SAMPLE}

    def get(command: str) -> Path:
        if command not in made:
            out = tmp_path_factory.mktemp(f"good-{command}") / "out"
            assert main([command, str(inputs[command]), "--out", str(out)]) == 0
            made[command] = out
        return made[command]
    return get
