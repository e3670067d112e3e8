"""The overlay fades traces of low confidence."""

import matplotlib.image
import numpy as np
import pytest

from rockmass.dfn import TraceMap
from rockmass.imaging.overlay import plot_overlay


def test_overlay_draws_a_confident_trace_stronger_than_a_doubtful_one(tmp_path):
    image = np.zeros((100, 200), dtype=np.uint8)  # black photo: only the traces have colour
    # traces in pixels (m_per_px = 1), v up: v = 70 is row 29.5 (upper half), v = 30 the lower half
    traces = TraceMap.from_segments([[20, 70, 180, 70], [20, 30, 180, 30]],
                                    {"confidence": [1.0, 0.0]})
    path = tmp_path / "overlay.png"
    plot_overlay(image, traces, path, m_per_px=1.0)
    rgb = matplotlib.image.imread(path)[..., :3]
    blue = (rgb[..., 2] > 0.4) & (rgb[..., 2] > rgb[..., 0] + 0.2)  # C0 at full opacity
    rows = np.flatnonzero(blue.any(axis=1))
    middle = rgb.shape[0] / 2
    assert rows.size and np.all(rows < middle)  # only the confident (upper) trace is strong



def test_a_large_photo_is_shown_area_averaged_not_strided(tmp_path):
    # 1-px black and white columns, 4000 px wide: area averaging to the figure's width shows them
    # as mid grey; taking every second column (as the overlay once did) showed black only
    image = np.zeros((2000, 4000), dtype=np.uint8)
    image[:, 1::2] = 255
    traces = TraceMap.from_segments([[100, 1000, 3900, 1000]], {"confidence": [1.0]})
    path = tmp_path / "overlay.png"
    plot_overlay(image, traces, path, m_per_px=1.0)
    grey = matplotlib.image.imread(path)[..., :3].mean(axis=2)
    h, w = grey.shape
    inside = grey[int(0.25 * h):int(0.4 * h), int(0.3 * w):int(0.7 * w)]  # above the trace
    assert abs(float(np.median(inside)) - 0.5) < 0.1


def test_the_photo_fills_the_figure_width_below_a_title_band(tmp_path):
    # a white photo on the white figure, framed by reading where its traces' colour reaches: a
    # trace along each edge of the photo marks its extent in the PNG
    h, w = 300, 900
    image = np.full((h, w), 255, dtype=np.uint8)
    # v up: the top edge is v = h - 0.5, the bottom v = -0.5; traces 1 px inside the edges
    traces = TraceMap.from_segments([[0.5, h - 1.5, w - 1.5, h - 1.5], [0.5, 0.5, w - 1.5, 0.5],
                                     [0.5, 0.5, 0.5, h - 1.5], [w - 1.5, 0.5, w - 1.5, h - 1.5]],
                                    {"confidence": [1.0] * 4})
    path = tmp_path / "overlay.png"
    plot_overlay(image, traces, path, m_per_px=1.0, title="t")
    rgb = matplotlib.image.imread(path)[..., :3]
    blue = (rgb[..., 2] > 0.4) & (rgb[..., 2] > rgb[..., 0] + 0.2)
    rows, cols = np.flatnonzero(blue.any(axis=1)), np.flatnonzero(blue.any(axis=0))
    height_px, width_px = rgb.shape[:2]
    assert width_px == 1100  # 10 in at 110 dpi
    # the photo spans the width but for a margin of about 0.05 in (5.5 px) each side
    assert cols.min() <= 10 and cols.max() >= width_px - 11
    # ... keeps its aspect ...
    assert (rows.max() - rows.min()) / (cols.max() - cols.min()) == pytest.approx(h / w, rel=0.03)
    # ... and sits at the bottom, below a band for the title
    assert height_px - rows.max() <= 10 and rows.min() > 30


@pytest.mark.parametrize("shape", [(40, 2000), (600, 900)])
def test_the_legend_stays_inside_the_figure_of_a_panorama_or_a_photo(tmp_path, monkeypatch, shape):
    # a 50:1 panorama leaves the photo band 0.2 in high, lower than a legend of ten sets
    from matplotlib.figure import Figure

    saved = []
    original = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: saved.append(fig) or original(fig, *a, **k))
    h, w = shape
    segments = [[w * k / 12, 5, w * (k + 1) / 12, h - 5] for k in range(10)]
    traces = TraceMap.from_segments(segments, {"confidence": [1.0] * 10})
    plot_overlay(np.full(shape, 128, np.uint8), traces, tmp_path / "overlay.png", m_per_px=1.0,
                 set_ids=np.arange(10))
    fig = saved[-1]
    legend = fig.axes[0].get_legend()
    assert len(legend.get_texts()) == 10
    box, frame = legend.get_window_extent(), fig.bbox
    assert box.x0 >= frame.x0 and box.y0 >= frame.y0 and box.x1 <= frame.x1 and box.y1 <= frame.y1
