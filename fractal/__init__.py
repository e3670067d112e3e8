"""Box-counting fractal dimension of joint-trace networks, with an honest error model.

- :func:`box_count` — raster (N x N grid, divisor box sizes, as Jiang et al.) or exact vector
  counting, fit of D with R^2, standard error, 95 % interval, local slopes and the spread over grid
  offsets; returns a :class:`BoxCount`.
- :func:`rasterize_traces` — draw traces with 1-pixel lines by one documented rule.
- :mod:`rockmass.fractal.reference` — reference fractals with exact dimensions.

The stage depends on nothing else in rockmass: numpy arrays (or any object with a ``segments()``
method, such as :class:`rockmass.dfn.TraceMap`) in, results out.
"""

from .boxcount import METHODS, BoxCount, box_count, grid_offsets
from .fit import LineFit, fit_loglog, local_slopes
from .image import divisors, prepare_binary_image, read_image
from .rasterize import LINE_RULES, rasterize_traces
from . import reference

__all__ = [
    "BoxCount", "box_count", "grid_offsets", "METHODS",
    "LineFit", "fit_loglog", "local_slopes",
    "divisors", "prepare_binary_image", "read_image",
    "LINE_RULES", "rasterize_traces",
    "reference",
]
