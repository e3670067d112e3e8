"""``report.html`` of ``rockmass run`` (:func:`rockmass.run_report.write_run_report`).

The run folder is built here without ``rockmass run``: each single-stage subcommand writes into its
stage folder (``DIR/<stage>/``, the run's contract) on small inputs, and ``run.json`` is written by
hand. The values the report shows are checked against the stage files read independently here.
"""

from __future__ import annotations

import base64
import json
import math
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from rockmass.cli import main
from rockmass.run_report import SECTIONS, STAGES, write_run_report

from . import _chromium
from .test_cli_solve import TINY  # 8 blocks, gravity then a short shaking: about a second

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
# the fixture's blocks are rigid: no plastic-zone map (tests/pipeline/test_solve_deformable.py
# draws one)
ALL_SECTIONS = {sid for sid, *_ in SECTIONS} - {"plastic"}
# issue 19 item 5: the traces stage adds the XYI diagram, the length distribution and the P21 map; the
# scanline adds the pole density, RQD bars and spacing histograms; dfn the pole density of its first
# realization; solve adds the contact maps
IMAGES_PER_STAGE = {"extract": 2, "traces": 5, "scanline": 4, "boxcount": 1, "dfn": 1, "blocks": 1, "solve": 3}


def _write_run_json(out: Path, stages, statuses=None) -> dict:
    doc = {"config": "run.toml", "config_hash": "c0ffee" * 10 + "abcd", "rockmass_version": "test",
           "stages": [], "total_wall_s": 0.0}
    for k, name in enumerate(stages):
        folder = out / name
        doc["stages"].append({
            "name": name, "dir": name, "status": (statuses or {}).get(name, "ran"),
            "hash": f"{k:02d}" + "ab" * 31, "wall_s": 0.5 + 1.25 * k,
            "outputs": sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())})
    doc["total_wall_s"] = sum(s["wall_s"] for s in doc["stages"])
    (out / "run.json").write_text(json.dumps(doc), encoding="utf-8")
    return doc


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """Every stage run into its folder on small inputs, run.json by hand, report written once."""
    from rockmass.imaging import save_synthetic_face, synthetic_face

    root = tmp_path_factory.mktemp("run_report")
    out = root / "out"
    face = synthetic_face("easy", seed=11, shape_px=(300, 450), m_per_px=0.02)
    photo = save_synthetic_face(face, root / "photo")["image"]
    config = root / "tiny.toml"
    config.write_text(TINY.format(kn="1e9", ks="5e8"), encoding="utf-8")
    traces = str(SAMPLES / "face_traces.geojson")
    commands = {
        "extract": ["extract", str(photo), "--m-per-px", "0.02"],
        "traces": ["traces", traces],
        "scanline": ["scanline", str(SAMPLES / "scanline_seed001.csv")],
        "boxcount": ["boxcount", traces],
        "dfn": ["dfn", str(SAMPLES / "dfn_seed001.toml"), "--realizations", "2"],
        "blocks": ["blocks", str(config)],
        "solve": ["solve", str(config)],
    }
    for name, argv in commands.items():
        assert main([*argv, "--out", str(out / name)]) == 0, name
    doc = _write_run_json(out, STAGES, {"traces": "reused"})
    path = write_run_report(out)
    return out, doc, path, _Page.parse(path)


class _Page(HTMLParser):
    """Sections (id -> text), tables (id -> rows of cell text), images and every src / href."""

    def __init__(self):
        super().__init__()
        self.sections, self.tables, self.images, self.links = {}, {}, [], []
        self.notes: dict[str, list[str]] = {}
        self._section = self._table = self._row = self._cell = self._note = None

    @classmethod
    def parse(cls, path: Path) -> _Page:
        page = cls()
        page.feed(path.read_text(encoding="utf-8"))
        return page

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.links += [v for k, v in attrs if k in ("src", "href") and v is not None]
        if tag == "section":
            self._section = a["id"].removeprefix("sec-")
            self.sections[self._section] = ""
        elif tag == "table":
            self._table = self.tables.setdefault(a.get("id") or f"anon{len(self.tables)}", [])
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = ""
        elif tag == "img":
            self.images.append((self._section, a))
        elif tag == "p" and a.get("class") == "note":
            self._note = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._row.append(self._cell)
            self._cell = None
        elif tag == "tr":
            self._table.append(self._row)
        elif tag == "p" and self._note is not None:
            self.notes.setdefault(self._section, []).append(self._note)
            self._note = None
        elif tag == "section":
            self._section = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data
        if self._note is not None:
            self._note += data
        if self._section is not None:
            self.sections[self._section] += data

    def rows(self, table_id: str) -> dict[str, list[str]]:
        """Rows of a table keyed by their first cell (header row included)."""
        return {r[0]: r for r in self.tables[table_id]}

    def cell(self, table_id: str, row: str, column: str) -> str:
        header = self.tables[table_id][0]
        return self.rows(table_id)[row][header.index(column)]


def _same(cell: str, value, rel=5e-4) -> bool:
    """A table cell shows ``value`` (4 significant digits)."""
    if isinstance(value, bool) or value is None:
        return cell == {True: "yes", False: "no", None: ""}[value]
    return math.isclose(float(cell), value, rel_tol=rel, abs_tol=1e-300)


def _copy(run_dir, tmp_path) -> Path:
    target = tmp_path / "out"
    shutil.copytree(run_dir[0], target)
    (target / "report.html").unlink()
    return target


def _stage_json(out: Path, stage: str, name: str):
    return json.loads((out / stage / name).read_text(encoding="utf-8"))


# ---------------------------------------------------------------------------------- sections --


def test_report_is_written_atomically_at_the_returned_path(run_dir, tmp_path, monkeypatch):
    from rockmass.dfn import atomic as _atomic

    out, _, path, _ = run_dir
    assert path == out / "report.html" and path.is_file()
    assert not list(out.glob(".tmp-*"))
    # a writer that fails halfway through the new page leaves the previous report as it was
    out = tmp_path / "out"
    shutil.copytree(run_dir[0], out)
    before = (out / "report.html").read_bytes()
    _write_run_json(out, STAGES, {s: "reused" for s in STAGES})  # the new page would differ

    class _HalfWritten:
        def __init__(self, handle):
            self.handle = handle

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return self.handle.__exit__(*exc)

        def write(self, data):
            self.handle.write(data[:len(data) // 2])
            self.handle.flush()
            raise OSError(28, "No space left on device")

    def half_open(*args, **kwargs):
        return _HalfWritten(open(*args, **kwargs))  # closed by _HalfWritten.__exit__

    monkeypatch.setattr(_atomic, "open", half_open, raising=False)
    with pytest.raises(OSError, match="No space left"):
        write_run_report(out)
    monkeypatch.undo()
    assert (out / "report.html").read_bytes() == before
    assert not list(out.glob(".tmp-*"))
    assert write_run_report(out).read_bytes() != before  # and the page did change


def test_each_json_file_is_parsed_once_per_report(run_dir, tmp_path, monkeypatch):
    from collections import Counter

    from rockmass import run_report

    out = _copy(run_dir, tmp_path)
    (out / "solve" / "result.json").write_text("not json", encoding="utf-8")  # a note, still once
    parsed, parse = Counter(), run_report._json

    def counting(path, root):
        parsed[Path(path).relative_to(out).as_posix()] += 1
        return parse(path, root)

    monkeypatch.setattr(run_report, "_json", counting)
    write_run_report(out)
    assert parsed["solve/result.json"] == 1 and parsed["traces/summary.json"] == 1
    assert parsed["dfn/realization_0000/summary.json"] == 1
    assert max(parsed.values()) == 1


def test_every_section_appears_when_every_stage_is_present(run_dir):
    page = run_dir[3]
    assert set(page.sections) == ALL_SECTIONS
    assert not page.notes, page.notes  # nothing missing, nothing unreadable


def test_sections_of_absent_stages_are_left_out(run_dir, tmp_path):
    out = tmp_path / "out"
    for stage in ("scanline", "boxcount"):
        shutil.copytree(run_dir[0] / stage, out / stage)
    _write_run_json(out, ["scanline", "boxcount"])
    page = _Page.parse(write_run_report(out))
    assert set(page.sections) == {"run", "inputs", "stereonet", "scanline", "boxcount", "intensity"}
    assert len(page.images) == 5 and not page.notes
    assert [r[0] for r in page.tables["t-timings"][1:]] == ["scanline", "boxcount"]


def test_only_the_solver_stage_gives_the_solver_sections(run_dir, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(run_dir[0] / "solve", out / "solve")
    _write_run_json(out, ["solve"])
    page = _Page.parse(write_run_report(out))
    assert set(page.sections) == {"run", "inputs", "solver", "displacement", "contacts", "histories",
                                  "energy"}


def test_every_image_is_an_embedded_png_and_nothing_is_referenced(run_dir):
    out, _, path, page = run_dir
    assert len(page.images) == sum(IMAGES_PER_STAGE.values())
    for section, attrs in page.images:
        prefix = "data:image/png;base64,"
        assert attrs["src"].startswith(prefix), (section, attrs["src"][:40])
        assert base64.b64decode(attrs["src"][len(prefix):])[:8] == b"\x89PNG\r\n\x1a\n"
        assert attrs.get("alt")
    assert all(link.startswith(("data:", "#sec-")) for link in page.links)
    text = path.read_text(encoding="utf-8")
    for external in ("http:", "https:", "file:", "url(", "<script", "<link", "@import"):
        assert external not in text, external
    assert str(out) not in text  # no absolute path of the run folder either


def test_images_per_section_follow_the_stages(run_dir):
    counts = {}
    for section, _ in run_dir[3].images:
        counts[section] = counts.get(section, 0) + 1
    assert counts == {"traces": 4, "topology": 1, "lengths": 1, "p21map": 1, "stereonet": 2, "scanline": 2,
                      "boxcount": 1, "dfn": 1, "blocks": 1, "displacement": 1, "contacts": 1, "histories": 1}


# ------------------------------------------------------------------------------------ values --


def test_run_summary_and_timings_equal_run_json(run_dir):
    _, doc, _, page = run_dir
    assert page.cell("t-run", "config hash", "value") == doc["config_hash"]
    assert page.cell("t-run", "rockmass version", "value") == doc["rockmass_version"]
    assert _same(page.cell("t-run", "total wall time (s)", "value"), doc["total_wall_s"])
    for s in doc["stages"]:
        assert page.cell("t-timings", s["name"], "status") == s["status"]
        assert _same(page.cell("t-timings", s["name"], "wall time (s)"), s["wall_s"])
        assert int(page.cell("t-timings", s["name"], "outputs")) == len(s["outputs"])
    assert page.cell("t-timings", "traces", "status") == "reused"


def test_inputs_table_lists_every_stage_manifest_input(run_dir):
    out, _, _, page = run_dir
    rows = page.tables["t-inputs"][1:]
    for stage in STAGES:
        for item in _stage_json(out, stage, "manifest.json")["inputs"]:
            assert [stage, item["path"], item["sha256"][:16], str(item["bytes"])] in rows


def test_box_count_table_equals_boxcount_json(run_dir):
    out, _, _, page = run_dir
    b = _stage_json(out, "boxcount", "boxcount.json")
    assert _same(page.cell("t-boxcount", "boxcount", "D"), b["dimension"])
    assert _same(page.cell("t-boxcount", "boxcount", "95 % CI low"), b["ci95"][0])
    assert _same(page.cell("t-boxcount", "boxcount", "95 % CI high"), b["ci95"][1])
    assert _same(page.cell("t-boxcount", "boxcount", "R²"), b["r2"])
    t = _stage_json(out, "traces", "summary.json")["Box-counting Dimension"]
    assert _same(page.cell("t-boxcount", "traces", "D"), t["value"])
    e = _stage_json(out, "extract", "summary.json")["statistics"]["Box-counting Dimension"]
    assert _same(page.cell("t-boxcount", "extract", "R²"), e["r2"])
    assert f"D = {b['dimension']:.4g}" in page.sections["boxcount"]


def test_intensity_table_equals_the_stage_summaries(run_dir):
    out, _, _, page = run_dir
    rows = {(r[0], r[3]): r for r in page.tables["t-intensity"][1:]}
    s = _stage_json(out, "scanline", "summary.json")
    assert _same(rows["P10", "scanline, all"][1], s["all"]["p10_per_m"])
    assert _same(rows["P10 (Terzaghi)", "scanline, set 1"][1], s["sets"][1]["p10_terzaghi_per_m"])
    t = _stage_json(out, "traces", "summary.json")
    assert _same(rows["P20", "traces, all"][1], t["Areal Frequency P20"]["value"])
    assert _same(rows["P21", "traces, all"][1], t["Fracture Intensity P21"]["value"])
    e = _stage_json(out, "extract", "summary.json")["statistics"]
    assert _same(rows["P21", "extract, all"][1], e["Fracture Intensity P21"]["value"])
    assert _same(rows["P21", "boxcount, counted window"][1],
                 _stage_json(out, "boxcount", "boxcount.json")["p21_per_m"])
    for i in (0, 1):
        d = _stage_json(out, "dfn", f"realization_{i:04d}/summary.json")
        assert _same(rows["P32 achieved", f"dfn, realization {i}"][1], d["total"]["achieved_p32"])
        sec = d["sections"][0]
        assert _same(rows["P21", f"dfn, realization {i}, section {sec['name']}"][1], sec["p21"])


def test_confident_table_equals_the_extract_summary(run_dir):
    # all traces against those of joint score >= the threshold, as extract/summary.json gives them
    out, _, _, page = run_dir
    summary = _stage_json(out, "extract", "summary.json")
    kept = summary["statistics_confident"]["statistics"]
    header = page.tables["t-confident"][0]
    assert header[1] == "all" and header[2].startswith("joint score")
    for key in ("Number of Traces", "Fracture Intensity P21"):
        assert _same(page.cell("t-confident", key, "all"), summary["statistics"][key]["value"])
        assert _same(page.cell("t-confident", key, header[2]), kept[key]["value"])


def test_confident_table_is_read_as_its_detector_allows(run_dir):
    # the learned detector's score-kept set is the conservative one (docs/imaging.md §7.1), the
    # ridge filter's the closer to a geologist's map: the page reads the detector "auto" kept
    out, _, path, _ = run_dir
    extraction = _stage_json(out, "extract", "summary.json")["extraction"]
    assert extraction["params"]["detector"] == "auto"
    choice = extraction["detector_choice"]
    kept = choice["kept"]
    ratio = choice.get("network_length_ratio")  # with the network among the candidates (§3.6)
    assert kept == ("ridge" if choice["agreement"] > 0.55
                    else "cnn" if ratio is not None and ratio >= choice["auto_network_ratio"]
                    else "learned")
    text = " ".join(path.read_text(encoding="utf-8").split())
    # the network's traces come through the learned chain and its filters
    assert ("the more conservative reading" in text) == (kept in ("learned", "cnn"))
    assert ("closer to a geologist" in text) == (kept == "ridge")


def test_dfn_table_gives_every_set_of_every_realization(run_dir):
    out, _, _, page = run_dir
    rows = {(r[0], r[1]): r for r in page.tables["t-dfn"][1:]}
    header = page.tables["t-dfn"][0]
    config = _stage_json(out, "dfn", "manifest.json")["config"]["dfn"]["sets"]
    assert len(rows) == 2 * len(config)
    for i in (0, 1):
        for s in _stage_json(out, "dfn", f"realization_{i:04d}/summary.json")["sets"]:
            row = rows[str(i), s["name"]]
            assert _same(row[header.index("P32 target (m²/m³)")], s["target_p32"])
            assert _same(row[header.index("P32 achieved (m²/m³)")], s["achieved_p32"])
            assert int(row[header.index("disks")]) == s["count"]
            spec = next(c for c in config if c["name"] == s["name"])
            orientation = row[header.index("orientation (dip/dip dir.)")]
            o = spec["orientation"]
            # dip/dip direction as the command line prints them (issue 19): "50/270"
            assert f"{round(o['dip_deg']):02d}/{round(o['dip_direction_deg']) % 360:03d}" in orientation
            assert f"r_min_m {spec['size']['r_min_m']:g}" in row[header.index("size law (radius)")]


def test_solver_and_energy_tables_equal_result_json(run_dir):
    out, _, _, page = run_dir
    r = _stage_json(out, "solve", "result.json")
    assert len(page.tables["t-solver"]) == 1 + len(r["stages"])
    for s in r["stages"]:
        name = s["name"]
        assert int(page.cell("t-solver", name, "steps")) == s["steps"]
        assert _same(page.cell("t-solver", name, "dt (s)"), s["time_step_s"])
        assert _same(page.cell("t-solver", name, "converged"), s["converged"])
        assert _same(page.cell("t-solver", name, "unbalanced ratio"), s["unbalanced_ratio"])
        assert _same(page.cell("t-solver", name, "max displacement (m)"),
                     s["max_displacement_equilibrium_m"])
        assert page.cell("t-solver", name, "failed blocks") == str(len(s["failed_blocks"])) \
            if not s["failed_blocks"] else page.cell("t-solver", name, "failed blocks").startswith(
                f"{len(s['failed_blocks'])}: ")
        assert page.cell("t-solver", name, "worst block ratio").endswith(
            f"(block {s['worst_block']})")
        for term, value in s["energy"].items():
            assert _same(page.cell("t-energy", term.removesuffix("_j"), name), value), term
    top = r["monitors"]["top"]
    assert _same(page.cell("t-monitors", "top", "final |u| (m)"), top["final_displacement_m"])


def _frame_displacements(path: Path) -> dict:
    import meshio
    import numpy as np

    mesh = meshio.read(path)
    ids = np.concatenate([np.asarray(d) for d in mesh.cell_data["block_id"]])
    disp = np.concatenate([np.asarray(d) for d in mesh.cell_data["displacement"]])
    return {int(b): d[:2] for b, d in zip(ids, disp)}


def test_displacement_map_is_the_last_frame_and_the_last_stage_alone(run_dir):
    import numpy as np

    out, _, _, page = run_dir
    frames = _stage_json(out, "solve", "result.json")["frames"]
    last = frames[-1]
    first = next(f for f in frames if f["stage"] == last["stage"])
    end = _frame_displacements(out / "solve" / last["file"])
    start = _frame_displacements(out / "solve" / first["file"])
    total_mm = 1e3 * max(float(np.hypot(*d)) for d in end.values())
    stage_mm = 1e3 * max(float(np.hypot(*(d - start[b]))) for b, d in end.items())
    text = page.sections["displacement"]
    assert last["file"] in text and f"during the last stage, {last['stage']}" in text
    shown = [float(part.split(" mm")[0]) for part in text.split("largest ")[1:]]
    assert shown == [pytest.approx(total_mm, rel=5e-4), pytest.approx(stage_mm, rel=5e-4)]


def test_blocks_table_equals_blocks_json(run_dir):
    out, _, _, page = run_dir
    q = _stage_json(out, "blocks", "blocks.json")["quality"]["n_blocks_by_region"]
    assert {r[0]: int(r[1]) for r in page.tables["t-blocks"][1:]} == q


def test_fitted_dfn_sets_show_the_fitted_orientation_and_size_law(run_dir, tmp_path):
    out = _copy(run_dir, tmp_path)
    shutil.rmtree(out / "dfn")
    assert main(["dfn", str(SAMPLES / "dfn_fit_seed001.toml"), "--realizations", "1",
                 "--out", str(out / "dfn")]) == 0
    page = _Page.parse(write_run_report(out))
    header, rows = page.tables["t-dfn"][0], {r[1]: r for r in page.tables["t-dfn"][1:]}
    fitted = _stage_json(out, "dfn", "fitted.json")["sets"]
    assert set(rows) == {s["name"] for s in fitted}
    for s in fitted:
        row, o = rows[s["name"]], s["orientation"]
        assert row[header.index("from")] == "fitted"
        orientation = row[header.index("orientation (dip/dip dir.)")]
        # issue 19: "79/009" as `rockmass dfn` and `rockmass scanline` print it (was "79.1/9.49")
        assert (f"{round(o['dip_deg']):02d}/{round(o['dip_direction_deg']) % 360:03d}, κ {o['kappa']:.3g}"
                in orientation)
        law = row[header.index("size law (radius)")]
        assert law.startswith(s["size"]["family"])
        assert f"alpha {s['size']['params']['alpha']:.4g}" in law
        assert ("(note: " in law) == bool(s["size"].get("note"))
    # a fit's note (an exponent the traces do not bound, dfn.size_fit) is shown beside its law
    doc = _stage_json(out, "dfn", "fitted.json")
    doc["sets"][0]["size"]["note"] = "alpha 20 is at the end of its search range"
    (out / "dfn" / "fitted.json").write_text(json.dumps(doc), encoding="utf-8")
    page_noted = _Page.parse(write_run_report(out))
    noted = {r[1]: r for r in page_noted.tables["t-dfn"][1:]}[doc["sets"][0]["name"]]
    assert noted[header.index("size law (radius)")].endswith("(note: alpha 20 is at the end of its search range)")
    rows = _stage_json(out, "dfn", "realization_0000/validation.json")["rows"]
    assert (f"realization 0: {sum(r['ok'] for r in rows)} of {len(rows)} field measures within "
            "tolerance") in page.sections["dfn"]


# ------------------------------------------------------- issue 19 item 5: what a geologist expects --


def _captions(page, section: str) -> list[str]:
    return [a["alt"] for s, a in page.images if s == section]


def test_geologist_figures_appear_in_their_sections(run_dir):
    page = run_dir[3]
    assert "XYI ternary diagram" in _captions(page, "topology")[0]
    assert "complementary cumulative, log-log" in _captions(page, "lengths")[0]
    assert "P21 on" in _captions(page, "p21map")[0]
    assert any("Density of the" in c and "multiples of a uniform density" in c
               for c in _captions(page, "stereonet"))
    assert [c.split(":")[0] for c in _captions(page, "scanline")] == [
        "RQD per group of the scanline", "Spacings between consecutive hits along the scanline (of one set"]
    assert "plastic shear slip" in _captions(page, "contacts")[0]


def test_dfn_pole_density_counts_the_disks_of_the_first_realization(run_dir):
    out, _, _, page = run_dir
    rows = (out / "dfn" / "realization_0000" / "fractures.csv").read_text().splitlines()[1:]
    caption = _captions(page, "dfn")[0]
    shown = -(-len(rows) // 5000)  # every k-th disk beyond 5000
    assert f"Density of the poles of the {len(rows[::shown])} disks of realization 0" in caption


def test_node_count_table_equals_the_trace_summary(run_dir):
    out, _, _, page = run_dir
    t = _stage_json(out, "traces", "summary.json")
    for node, count in t["Node Counts"].items():
        assert page.cell("t-nodes", node, "value") == str(count)
    assert _same(page.cell("t-nodes", "Connections per Branch", "value"), t["Connections per Branch"]["value"])


def test_trace_length_caption_states_the_censoring_of_the_summary(run_dir):
    out, _, _, page = run_dir
    t = _stage_json(out, "traces", "summary.json")["traces"]
    one = sum(1 for e in t["end_class"] if list(e).count("E") == 1)
    both = sum(1 for e in t["end_class"] if list(e).count("E") == 2)
    caption = _captions(page, "lengths")[0]
    assert (f"{len(t['length'])} traces, {sum(t['censored'])} censored by the window edge ({one} with one "
            f"end, {both} with both ends on it") in caption
    assert "no size law was fitted in this run" in caption  # the fixture's dfn stage fits nothing


def test_p21_map_caption_adds_up_to_the_summary_p21(run_dir):
    out, _, _, page = run_dir
    t = _stage_json(out, "traces", "summary.json")
    caption = _captions(page, "p21map")[0]
    total = sum(t["traces"]["length"])
    assert f"{total:.4g} m of traces on {t['Area']['value']:.4g} m²" in caption
    assert f"P21 {t['Fracture Intensity P21']['value']:.4g} m/m² overall" in caption


def test_rqd_table_equals_the_scanline_summary(run_dir):
    out, _, _, page = run_dir
    s = _stage_json(out, "scanline", "summary.json")
    for label, group in [("all", s["all"])] + [(f"set {g['set']}", g) for g in s["sets"]]:
        assert _same(page.cell("t-rqd", label, "RQD measured (%)"), group["rqd_direct_percent"])
        assert _same(page.cell("t-rqd", label, "RQD Priest & Hudson (%)"), group["rqd_priest_hudson_percent"])
        assert page.cell("t-rqd", label, "hits") == str(group["n_intersections"])


def test_fitted_size_law_is_drawn_over_the_lengths_of_the_traces_it_was_fitted_to(run_dir, tmp_path):
    out = _copy(run_dir, tmp_path)
    manifest = _stage_json(out, "dfn", "manifest.json")
    traces = _stage_json(out, "traces", "summary.json")["input"]["path"]
    manifest.setdefault("config", {}).setdefault("dfn", {})["fit"] = {"faces": [{"file": traces}]}
    (out / "dfn" / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    law = {"family": "power_law", "params": {"alpha": 3.0, "r_min_m": 0.5, "r_max_m": 20.0},
           "n_traces": 10, "ok": True}
    (out / "dfn" / "fitted.json").write_text(json.dumps({"sets": [{"name": "S1", "size": law}]}))
    page = _Page.parse(write_run_report(out))
    caption = _captions(page, "lengths")[0]
    assert "line: the trace-length survival S(l) of the disk radius laws fitted in the dfn stage" in caption
    assert "S1: power_law alpha 3, r_min_m 0.5, r_max_m 20" in caption


def test_fitted_size_law_is_found_from_the_run_relative_path_rockmass_run_records(run_dir,
                                                                                   tmp_path):
    """``rockmass run`` records a face file of its own run as ``<run>/traces/...`` (issue 18: hashes
    that do not depend on --out): the report maps it back to this run folder."""
    out = _copy(run_dir, tmp_path)
    manifest = _stage_json(out, "dfn", "manifest.json")
    traces = Path(_stage_json(out, "traces", "summary.json")["input"]["path"])
    (out / "given").mkdir()  # the traces stage's input, as a file of this run folder
    (out / "given" / traces.name).write_bytes(traces.read_bytes())
    summary = _stage_json(out, "traces", "summary.json")
    summary["input"]["path"] = str(out / "given" / traces.name)
    (out / "traces" / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    portable = f"<run>/given/{traces.name}"
    manifest.setdefault("config", {}).setdefault("dfn", {})["fit"] = {"faces": [{"file": portable}]}
    (out / "dfn" / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    law = {"family": "power_law", "params": {"alpha": 3.0, "r_min_m": 0.5, "r_max_m": 20.0},
           "n_traces": 10, "ok": True}
    (out / "dfn" / "fitted.json").write_text(json.dumps({"sets": [{"name": "S1", "size": law}]}))
    caption = _captions(_Page.parse(write_run_report(out)), "lengths")[0]
    assert "S1: power_law alpha 3, r_min_m 0.5, r_max_m 20" in caption


def test_summaries_without_the_new_numbers_give_notes_not_a_crash(run_dir, tmp_path):
    out = _copy(run_dir, tmp_path)
    s = _stage_json(out, "scanline", "summary.json")
    del s["intersections"]
    for group in [s["all"], *s["sets"]]:
        del group["spacings_m"]
    (out / "scanline" / "summary.json").write_text(json.dumps(s), encoding="utf-8")
    t = _stage_json(out, "traces", "summary.json")
    del t["P21 Map"]
    t["Node Counts"] = {"I": 0, "Y": 0, "X": 0, "E": 4}   # every end censored
    t["traces"]["length"], t["traces"]["censored"] = [], []
    (out / "traces" / "summary.json").write_text(json.dumps(t), encoding="utf-8")
    (out / "solve" / "contacts.vtu").unlink()
    page = _Page.parse(write_run_report(out))
    notes = {k: " ".join(v) for k, v in page.notes.items()}
    assert "lists no poles" in notes["stereonet"]
    assert "holds no spacings" in notes["scanline"] and "t-rqd" in page.tables
    assert "no I, Y or X node: no ternary diagram" in notes["topology"]
    assert "lists no trace lengths" in notes["lengths"]
    assert "has no P21 map" in notes["p21map"]
    assert "solve/contacts.vtu is missing" in notes["contacts"]
    for section in ("topology", "lengths", "p21map", "contacts"):
        assert not _captions(page, section)


def test_a_map_without_trace_statistics_gives_notes_in_the_trace_sections(run_dir, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(run_dir[0] / "extract", out / "extract")
    e = _stage_json(out, "extract", "summary.json")
    e["statistics"] = None                                # extract found no trace
    (out / "extract" / "summary.json").write_text(json.dumps(e), encoding="utf-8")
    _write_run_json(out, ["extract"])
    page = _Page.parse(write_run_report(out))
    for section in ("topology", "lengths", "p21map"):
        assert "has no trace statistics (no trace was found)" in " ".join(page.notes[section])


# ---------------------------------------------------------------------------- bad or missing --


def test_corrupt_and_missing_stage_files_give_notes_not_a_crash(run_dir, tmp_path):
    out = _copy(run_dir, tmp_path)
    (out / "boxcount" / "boxcount.json").write_text('{"dimension": 1.6', encoding="utf-8")
    rose = out / "traces" / "rose.png"
    rose.write_bytes(rose.read_bytes()[:500])
    (out / "scanline" / "stereonet.png").unlink()
    (out / "solve" / "history.csv").write_text("time_s,stage,top_ux_m\n0.0,gravity,abc\n")
    (out / "solve" / "result.json").write_text("not json", encoding="utf-8")
    last = max((out / "solve").glob("blocks_*.vtu"))
    last.write_text("<VTKFile broken", encoding="utf-8")
    (out / "dfn" / "realization_0001" / "summary.json").unlink()
    page = _Page.parse(write_run_report(out))
    assert set(page.sections) == ALL_SECTIONS
    notes = {k: " ".join(v) for k, v in page.notes.items()}
    assert "boxcount/boxcount.json is not readable JSON" in notes["boxcount"]
    assert "traces/rose.png cannot be shown (truncated PNG" in notes["traces"]
    assert "scanline/stereonet.png is missing" in notes["stereonet"]
    assert "solve/history.csv holds a value that is not a number" in notes["histories"]
    assert "solve/result.json is not readable JSON" in notes["solver"]
    assert "solve/result.json is not readable JSON" in notes["energy"]
    assert f"solve/{last.name} is not a readable VTU file" in notes["displacement"]
    assert "dfn/realization_0001/summary.json is missing" in notes["dfn"]
    # what is still readable is still shown (the pole density is drawn from the scanline summary,
    # the contact maps from contacts.vtu, without the broken frame's outlines)
    assert {s for s, _ in page.images} == {"traces", "topology", "lengths", "p21map", "stereonet", "scanline",
                                           "boxcount", "dfn", "blocks", "contacts"}
    assert len([s for s, _ in page.images if s == "traces"]) == 3
    assert "t-intensity" in page.tables and "t-blocks" in page.tables
    assert {r[0] for r in page.tables["t-dfn"][1:]} == {"0"}  # the readable realization


def test_missing_or_corrupt_run_json_gives_a_note_and_the_stage_sections(run_dir, tmp_path):
    out = _copy(run_dir, tmp_path)
    (out / "run.json").unlink()
    page = _Page.parse(write_run_report(out))
    assert set(page.sections) == ALL_SECTIONS
    assert "run.json is missing" in page.notes["run"][0]
    (out / "run.json").write_text("[1, 2]", encoding="utf-8")
    page = _Page.parse(write_run_report(out))
    assert "run.json is not a run record" in page.notes["run"][0]
    assert set(page.sections) == ALL_SECTIONS


def test_a_run_without_any_stage_gives_a_short_report(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    _write_run_json(out, [])
    page = _Page.parse(write_run_report(out))
    assert set(page.sections) == {"run", "inputs"}
    assert page.notes["inputs"] == ["No input file recorded."]


# ------------------------------------------------------------------------------------ browser --


@pytest.mark.skipif(_chromium.chromium() is None, reason=_chromium.SKIP_REASON)
def test_report_renders_in_headless_chromium_with_every_image_loaded(run_dir, tmp_path):
    """Open report.html in headless Chromium (no network): every <img> decodes; a screenshot is
    kept as an artifact (in $ROCKMASS_TEST_ARTIFACTS when set)."""
    path = run_dir[2]
    loaded, total = _chromium.count_loaded_images(path, tmp_path)
    assert total == sum(IMAGES_PER_STAGE.values()) and loaded == total
    shot = _chromium.screenshot(path, tmp_path / "run_report.png", size=(1250, 3000))
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_histories_section_reports_a_failed_monitor_as_failed(tmp_path):
    """A monitor whose block failed: its table row says so instead of a final displacement, and
    its curve ends where the block was taken out (the rows after, frozen, are not drawn)."""
    import csv

    from rockmass.report_solve import _removal_row, _section_histories
    from rockmass.run_report import _Run

    solve = tmp_path / "solve"
    solve.mkdir()
    rows = [("settle", 0.0, 0.0, 0.0), ("settle", 0.1, 0.0, -0.0001), ("arch", 0.2, 0.0, -0.004),
            ("arch", 0.3, 0.001, -0.02), ("arch", 0.4, 0.001, -0.02), ("arch", 0.5, 0.001, -0.02)]
    with (solve / "history.csv").open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["time_s", "stage", "crown_ux_m", "crown_uy_m", "wall_ux_m", "wall_uy_m"])
        for stage, t, ux, uy in rows:
            writer.writerow([t, stage, ux, uy, 0.0005 * t, 0.0])
    failed = {"stage": "arch", "mechanism": "fall", "displacement_at_removal_m": 0.02, "time_s": 0.32}
    monitors = {"crown": {"block": 7, "stages": [], "failed": failed},
                "wall": {"block": 3, "stages": [], "final_ux_m": 0.00025, "final_uy_m": 0.0,
                         "final_displacement_m": 0.00025}}
    (solve / "result.json").write_text(json.dumps({"monitors": monitors}))
    history = {"stage": [r[0] for r in rows], "time_s": [r[1] for r in rows]}
    assert _removal_row(history, failed) == 3  # the last row at or before the removal (0.32 s)
    legacy = {k: v for k, v in failed.items() if k != "time_s"}  # a result.json before session 24
    assert _removal_row(history, legacy) == 5  # the stage's last row
    html = _section_histories(_Run(tmp_path))
    assert "failed in stage arch (fall): no displacement" in html
    assert "ends with a cross where the block was taken out" in html
    assert "0.00025" in html  # the other monitor keeps its final displacement
