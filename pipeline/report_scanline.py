"""The scanline sections of ``report.html`` (:mod:`rockmass.run_report`): the stereonet with the
contoured pole density, and the spacings and RQD of the survey.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .html_report import figure, fmt, note, png_base64, table
from .report_files import _image, _Note

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


def _section_stereonet(run: _Run) -> str:
    """Poles of the scanline survey with the fitted sets, and their density contoured."""
    poles = _image(run, "scanline", "stereonet.png",
                   "Poles to joints of the scanline (lower hemisphere, equal area), by set", "small")
    try:
        density = _pole_density_figure(run)
    except _Note as exc:
        density = note(f"{exc}.")
    return poles + density


def _pole_density_figure(run: _Run) -> str:
    """The contoured stereonet of the scanline's poles (dip / dip direction of its summary)."""
    from .dfn.orientation import normal_from_dip
    from .dfn.stereonet import kamb_kappa, plot_pole_density

    doc = run.json("scanline", "summary.json")
    hits = doc.get("intersections") or {}
    dip, azimuth = hits.get("dip_deg") or [], hits.get("dip_direction_deg") or []
    if not dip or len(dip) != len(azimuth):
        raise _Note("scanline/summary.json lists no poles (no intersection): no density to contour")
    poles = normal_from_dip(dip, azimuth)
    means = [s["mean_pole_xyz"] for s in doc.get("sets") or [] if s.get("mean_pole_xyz")]
    fig = plot_pole_density(poles, set_means=means or None)
    caption = (f"Density of the {len(dip)} poles of the scanline in multiples of a uniform density "
               f"(lower hemisphere, equal area): a Fisher kernel per pole, k = {fmt(kamb_kappa(len(dip)), 3)} "
               "(Kamb's counting circle at 3 σ, in Vollmer's exponential form); squares: set mean poles. "
               "Not corrected for the scanline's orientation bias (Terzaghi)")
    return figure(caption, png_base64(fig), "small")


def _section_scanline(run: _Run) -> str:
    """RQD per group (table and bars) and the spacing histograms with their fitted laws."""
    from .dfn.plots import plot_rqd, plot_spacings

    doc = run.json("scanline", "summary.json")
    line = doc.get("scanline") or {}
    groups = [("all", doc.get("all") or {})] + [(f"set {g.get('set')}", g) for g in doc.get("sets") or []]
    rows = [[label, fmt(g.get("n_intersections")), fmt(g.get("p10_per_m")), fmt(g.get("rqd_direct_percent")),
             fmt(g.get("rqd_priest_hudson_percent")), fmt((g.get("spacing_m") or {}).get("mean_m")),
             fmt(g.get("mean_normal_spacing_m")), fmt((g.get("spacing_m") or {}).get("preferred"))]
            for label, g in groups]
    threshold = line.get("rqd_threshold_m", 0.1)
    head = ["group", "hits", "P10 (1/m)", "RQD measured (%)", "RQD Priest & Hudson (%)",
            "mean spacing along the line (m)", "mean spacing normal to the set (m)", "spacing law (AIC)"]
    parts = [f"<p>Scanline trend/plunge {fmt(line.get('trend_deg'), 3)}/{fmt(line.get('plunge_deg'), 3)}, "
             f"length {fmt(line.get('length_m'))} m; RQD counts pieces of at least {fmt(threshold)} m "
             "(Deere 1964), measured on the line and expected from P10 (Priest &amp; Hudson 1976).</p>",
             table(head, rows, "t-rqd")]
    fig = plot_rqd([label for label, _ in groups], [g.get("rqd_direct_percent") for _, g in groups],
                   [g.get("rqd_priest_hudson_percent") for _, g in groups], threshold_m=float(threshold))
    parts.append(figure("RQD per group of the scanline: measured and from P10", png_base64(fig), "small"))
    if all("spacings_m" not in g for _, g in groups):
        return "".join(parts) + note("scanline/summary.json holds no spacings (written by an older "
                                     "rockmass): rerun the scanline stage for the histograms.")
    fig = plot_spacings([(label, g.get("spacings_m") or [], g.get("spacing_m")) for label, g in groups])
    parts.append(figure("Spacings between consecutive hits along the scanline (of one set: between that "
                        "set's hits), with the exponential and lognormal laws fitted by maximum "
                        "likelihood (solid: the one preferred by AIC)", png_base64(fig)))
    return "".join(parts)

