"""``report.html`` of a study: one self-contained page (PNG images embedded as base64, no script,
no network) with

- D_box against the maximum displacement, one colour per value of the colouring field (θ, as in
  Jiang et al., seed 000 Figs. 7–8): every realization as a dot, the mean of each parameter
  combination with ± one standard deviation over its realizations in both directions;
- the spread over realizations: D_box and displacement of every combination;
- a summary table per combination (mean ± sd, n) and the table of every case (as results.csv).
"""

from __future__ import annotations

import base64
import html
import json
import math
from collections import OrderedDict

from .html_report import BASE_CSS, figure, pyplot
from .html_report import fmt as _fmt
from .html_report import png_base64 as _png
from .html_report import table as _table
from .study_config import params_text

__all__ = ["write_report", "colour_field", "groups"]


def colour_field(study, cases) -> str | None:
    """The field that colours the plots: ``study.colour_by``, else θ when it varies, else the
    first varying field."""
    if study.colour_by:
        return study.colour_by
    varying = []
    for c in cases:
        for p in c.params:
            if p not in varying:
                varying.append(p)
    for p in varying:
        if p.endswith("theta_deg"):
            return p
    return varying[0] if varying else None


def _value(case, path):
    from .study_config import get_path

    if path in case.params:
        return case.params[path]
    return get_path(case.raw, path)


def _label(value) -> str:
    if isinstance(value, float) and value.is_integer():
        return f"{value:g}"
    return json.dumps(value) if isinstance(value, (list, dict)) else str(value)


def groups(cases, records: dict) -> "OrderedDict[str, list]":
    """Parameter combination (the case's params as text) -> [(case, record)] over realizations."""
    out: OrderedDict[str, list] = OrderedDict()
    for c in cases:
        rec = records.get(c.case_id)
        if rec is None:
            continue
        key = json.dumps(c.params, sort_keys=True)
        out.setdefault(key, []).append((c, rec))
    return out


def _mean_sd(values):
    vals = [v for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return None, None, 0
    m = sum(vals) / len(vals)
    sd = math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1)) if len(vals) > 1 else 0.0
    return m, sd, len(vals)


def _disp_key(study) -> str:
    return "max_displacement_boundary_m" if study.displacement == "boundary" else \
        "max_displacement_overall_m"


def _figures(study, cases, finished) -> list[tuple[str, str]]:
    plt = pyplot()
    figs = []
    key = _disp_key(study)
    cfield = colour_field(study, cases)
    grouped = groups(cases, finished)
    has_disp = any(r.get(key) is not None for r in finished.values())
    colour_values = []
    for c in cases:
        v = _label(_value(c, cfield)) if cfield else "all"
        if v not in colour_values:
            colour_values.append(v)
    cmap = plt.get_cmap("tab10")
    colours = {v: cmap(i % 10) for i, v in enumerate(colour_values)}
    cname = (cfield or "").rsplit(".", 1)[-1]
    symbol = "θ" if cname == "theta_deg" else cname

    # 1. D_box vs maximum displacement (seed 000 Figs. 7-8)
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    ylab = f"maximum displacement {'around the excavation' if study.displacement == 'boundary' else ''} (mm)"
    series: dict[str, list] = {}
    scale = 1e3 if has_disp else 1.0
    all_y = [r.get(key if has_disp else "p21_per_m") * scale for r in finished.values()
             if r.get(key if has_disp else "p21_per_m") is not None]
    positive = [y for y in all_y if y > 0]
    log_y = bool(positive) and max(positive) > 100 * min(positive)
    for members in grouped.values():
        c0 = members[0][0]
        cv = _label(_value(c0, cfield)) if cfield else "all"
        ds = [r.get("d_box") for _, r in members]
        ys = [r.get(key) if has_disp else r.get("p21_per_m") for _, r in members]
        pts = [(d, y * scale) for d, y in zip(ds, ys) if d is not None and y is not None]
        if not pts:
            continue
        settled = [r.get("converged") is not False for _, r in members
                   if r.get("d_box") is not None and (r.get(key) if has_disp else r.get("p21_per_m")) is not None]
        for filled in (True, False):
            sel = [p for p, ok in zip(pts, settled) if ok == filled]
            if sel:
                ax.scatter([p[0] for p in sel], [p[1] for p in sel], s=16, alpha=0.5,
                           facecolors=colours[cv] if filled else "none", edgecolors=colours[cv],
                           linewidths=0 if filled else 1.0)
        md, sd_d, _ = _mean_sd([p[0] for p in pts])
        my, sd_y, _ = _mean_sd([p[1] for p in pts])
        yerr = None
        if sd_y:  # on a log axis the bar stops short of zero
            yerr = [[min(sd_y, 0.9 * my) if log_y else sd_y], [sd_y]]
        ax.errorbar(md, my, xerr=sd_d or None, yerr=yerr, fmt="o", ms=6,
                    color=colours[cv], capsize=3)
        series.setdefault(cv, []).append((md, my))
    for cv, pts in series.items():
        pts.sort()
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color=colours[cv], lw=1.2,
                label=f"{symbol} = {cv}" + ("°" if cname.endswith("_deg") else ""))
    if log_y:
        ax.set_yscale("log")  # settled cases (mm) and falling blocks (m) on one plot
    ax.set_xlabel("fractal dimension D_box (360 × 360 box counting)")
    ax.set_ylabel(ylab if has_disp else "P21 (m/m²)")
    ax.set_title("Maximum displacement versus fractal dimension" if has_disp
                 else "Joint intensity versus fractal dimension (no [solve] section)")
    if series:
        ax.legend(title=None, frameon=False)
    ax.grid(alpha=0.3)
    figs.append(("D_box versus maximum displacement, coloured by " + (cfield or "case")
                 + "; dots: realizations (hollow: a stage did not converge, e.g. blocks still "
                 "falling), markers: mean ± sd over realizations" if has_disp else
                 "D_box versus P21 (the base config has no [solve] section)", _png(fig)))
    plt.close(fig)

    # 2. spread over realizations, per combination
    labels, dvals, yvals, cols = [], [], [], []
    for gkey, members in grouped.items():
        c0 = members[0][0]
        labels.append(params_text(c0.params) or "base")
        dvals.append([r.get("d_box") for _, r in members if r.get("d_box") is not None])
        yvals.append([r.get(key) * 1e3 for _, r in members if r.get(key) is not None])
        cols.append(colours[_label(_value(c0, cfield)) if cfield else "all"])
    if labels:
        panels = 2 if has_disp else 1
        fig, axes = plt.subplots(panels, 1, figsize=(max(6.0, 0.45 * len(labels) + 2), 2.6 * panels + 1),
                                 sharex=True, squeeze=False)
        for ax, vals, name in zip(axes[:, 0], (dvals, yvals), ("D_box", "max displacement (mm)")):
            for i, (v, col) in enumerate(zip(vals, cols)):
                ax.scatter([i] * len(v), v, s=14, color=col, alpha=0.7, linewidths=0)
                m, sd, n = _mean_sd(v)
                if m is not None:
                    err = None
                    if sd:
                        err = [[min(sd, 0.9 * m) if (log_y and name.startswith("max")) else sd],
                               [sd]]
                    ax.errorbar(i + 0.18, m, yerr=err, fmt="_", ms=10, color="k", capsize=3)
            ax.set_ylabel(name)
            if log_y and name.startswith("max"):
                ax.set_yscale("log")
            ax.grid(alpha=0.3)
        axes[-1, 0].set_xticks(range(len(labels)))
        axes[-1, 0].set_xticklabels(labels, rotation=60, ha="right", fontsize=7)
        figs.append(("Spread over realizations (dots) with mean ± sd (black) for every parameter "
                     "combination", _png(fig)))
        plt.close(fig)
    return figs


def _model_thumbnails(study, cases, finished, config_path, limit: int = 6) -> list[tuple[str, str]]:
    """Block plots of representative cases: for each colour value, the realization-0 cases with
    the smallest and the largest D_box (models rebuilt from their configs, a second or so each)."""
    import tempfile
    from pathlib import Path

    from .blockgen import plot_blocks
    from .study import _build_model

    cfield = colour_field(study, cases)
    key = _disp_key(study)
    picks: dict[str, list] = {}
    for c in cases:
        rec = finished.get(c.case_id)
        if rec is None or rec.get("d_box") is None or c.realization != 0:
            continue
        picks.setdefault(_label(_value(c, cfield)) if cfield else "all", []).append((c, rec))
    chosen = []
    for members in picks.values():
        members.sort(key=lambda m: m[1]["d_box"])
        for m in (members[0], members[-1]):
            if m not in chosen:
                chosen.append(m)
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, (c, rec) in enumerate(chosen[:limit]):
            try:
                model = _build_model(c.document, config_path)
                path = plot_blocks(model, Path(tmp) / f"case{i}.png", dpi=50)
            except Exception:  # noqa: BLE001 - a missing thumbnail must not stop the report
                continue
            disp = rec.get(key)
            cap = (f"case {c.index}: {params_text(c.params) or 'base'}; D_box "
                   f"{rec['d_box']:.3f}, {model.n_blocks} blocks"
                   + (f", max displacement {disp * 1e3:.3g} mm" if disp is not None else ""))
            out.append((cap, base64.b64encode(path.read_bytes()).decode("ascii")))
    return out


def write_report(path, document, cases, finished: dict, failed: dict, summary: dict,
                 config_path) -> None:
    """Write ``report.html`` (atomically)."""
    from .atomic import atomic_write_text
    from .study import results_rows

    study = document.study
    key = _disp_key(study)
    figs = _figures(study, cases, finished) if finished else []
    grouped = groups(cases, finished)
    srows = []
    for members in grouped.values():
        c0 = members[0][0]
        row = [params_text(c0.params) or "base", str(len(members))]
        for k, scale in (("d_box", 1.0), ("d_box_r2", 1.0), ("p21_per_m", 1.0), ("n_blocks", 1.0),
                         (key, 1e3)):
            m, sd, n = _mean_sd([(r.get(k) * scale) if r.get(k) is not None else None
                                 for _, r in members])
            row.append("" if m is None else f"{m:.4g} ± {sd:.2g}")
        row.append(f"{sum(1 for _, r in members if r.get('converged') is True)}/{len(members)}")
        row.append(", ".join(str(r.get("detached_blocks", "")) for _, r in members))
        srows.append(row)
    sheader = ["parameters", "n", "D_box", "R²", "P21 (1/m)", "blocks", "max displacement (mm)",
               "converged", "detached blocks"]
    header, rows = results_rows(cases, {**finished, **failed}, study.displacement)
    rows = [[_fmt(float(x)) if _is_float(x) else x for x in r] for r in rows]
    try:
        thumbs = _model_thumbnails(study, cases, finished, config_path) if finished else []
    except Exception:  # noqa: BLE001
        thumbs = []
    thumbs_html = "".join(figure(cap, b64, "thumb") for cap, b64 in thumbs)
    images = "".join(figure(cap, b64) for cap, b64 in figs)
    info = (f"{summary['finished']} of {summary['cases']} cases finished, {summary['failed']} "
            f"failed, {summary['skipped']} reused from an earlier run; executor: "
            f"{summary['executor']}; status: {summary['status']}")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>rockmass study report</title>
<style>
{BASE_CSS}.thumbs {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figure.thumb {{ width: 360px; margin: 0; }}
</style></head><body>
<h1>rockmass study</h1>
<p>Config: <code>{html.escape(str(config_path))}</code>. {html.escape(info)}.</p>
<p>D_box: box counting of the joint network (joint sets and traces clipped to the domain, without
excavation outlines or dangling-end extensions) rasterised on a {(document.fractal.grid if document.fractal else 360)}
× {(document.fractal.grid if document.fractal else 360)} grid (Jiang et al. §4.1). Maximum displacement:
{'of the blocks on the excavation boundary' if study.displacement == 'boundary' else 'of any block'}
after the last DEM stage, from the initial equilibrium.</p>
<h2>Plots</h2>
{images or '<p>No finished case yet.</p>'}
<h2>Block models</h2>
<p>For each {html.escape(colour_field(study, cases) or 'case')} value, the realization-0 cases with the
smallest and largest D_box (excavation stages shaded; edges coloured by joint set).</p>
<div class="thumbs">{thumbs_html or '<p>None.</p>'}</div>
<h2>Per parameter combination (mean ± sd over realizations)</h2>
{_table(sheader, srows)}
<h2>All cases (results.csv)</h2>
{_table(header, rows)}
</body></html>
"""
    atomic_write_text(path, page)


def _is_float(text: str) -> bool:
    if not text or not any(ch in text for ch in ".e") or text.startswith(("[", "{")):
        return False
    try:
        float(text)
    except ValueError:
        return False
    return True
