"""Block models: a 2D section cut by joint sets or DFN traces, with excavations.

Public names
------------
:func:`build`
    Domain + joint sets / traces + excavation stages -> :class:`BlockModel`
    (:mod:`rockmass.blockgen.builder`).
:class:`BlockModel`, :data:`CONTACT_KINDS`, :func:`polygon_properties`
    The model handed to the DEM (:mod:`rockmass.blockgen.model`).
:class:`Cracks`, :data:`CRACK_PATTERNS`, :data:`SOURCE_CRACK`
    Potential-crack subdivision of intact blocks (:mod:`rockmass.blockgen.cracks`).
:class:`JointSet`
    UDEC-style joint set (:mod:`rockmass.blockgen.joints`).
:class:`Excavation`, :func:`circle`, :func:`horseshoe`, :func:`arched_cavern`, :func:`rectangle`,
:func:`polygon_excavation`, :func:`circle_perimeter_m`
    Excavation stages (:mod:`rockmass.blockgen.excavations`).
:func:`check_model`
    The invariants (area balance, no overlap, shared edges, convexity) (:mod:`rockmass.blockgen.checks`).
:func:`to_json_dict`, :func:`from_json_dict`, :func:`write_json`, :func:`read_json`, :func:`write_vtu`
    Files (:mod:`rockmass.blockgen.blockio`); :func:`plot_blocks` (:mod:`rockmass.blockgen.plots`).
:class:`Tolerances`, :func:`model_tolerances`
    Every tolerance with its reason (:mod:`rockmass.blockgen.tolerances`).

``rockmass.blockgen`` may import ``rockmass.dfn`` but never the pipeline modules.
"""

from .blockio import from_json_dict, read_json, to_json_dict, write_json, write_vtu
from .builder import DANGLING_CHOICES, build
from .checks import check_model
from .cracks import CRACK_PATTERNS, Cracks
from .excavations import (DEFAULT_CIRCLE_SIDES, Excavation, arched_cavern, circle,
                          circle_perimeter_m, horseshoe, polygon_excavation, rectangle)
from .joints import SPACING_DISTRIBUTIONS, JointSet
from .model import CONTACT_KINDS, SOURCE_CONVEX_CUT, SOURCE_CRACK, BlockModel, polygon_properties
from .tolerances import Tolerances, model_tolerances

__all__ = ["build", "DANGLING_CHOICES", "BlockModel", "CONTACT_KINDS", "polygon_properties",
           "JointSet", "SPACING_DISTRIBUTIONS", "Excavation", "circle", "horseshoe", "arched_cavern",
           "rectangle", "polygon_excavation", "circle_perimeter_m", "DEFAULT_CIRCLE_SIDES",
           "Tolerances", "model_tolerances", "check_model", "to_json_dict", "from_json_dict",
           "write_json", "read_json", "write_vtu", "plot_blocks", "Cracks", "CRACK_PATTERNS",
           "SOURCE_CONVEX_CUT", "SOURCE_CRACK"]


def __getattr__(name):  # matplotlib only when a plot is drawn
    if name == "plot_blocks":
        from .plots import plot_blocks

        return plot_blocks
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
