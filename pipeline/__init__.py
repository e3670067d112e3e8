"""rockmass: from face photographs and scanlines to a solved jointed rock-mass model.

The stages are sub-packages, imported on demand so that ``import rockmass`` stays light:

- :mod:`rockmass.imaging` — face photographs to joint traces;
- :mod:`rockmass.fractal` — box-counting fractal dimension of trace networks;
- :mod:`rockmass.dfn` — trace maps, scanlines, fracture statistics and DFN generation;
- :mod:`rockmass.blockgen` — block models cut by joints and excavations;
- :mod:`rockmass.solver` — the distinct element (DEM) core.

The package layout, data flow and conventions are described in ``docs/design.md``.
"""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("rockmass")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
