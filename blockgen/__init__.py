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
:class:`JointSet`, :func:`joint_set_segments`
    UDEC-style joint set; the joints of a model's sets drawn as :func:`build` draws them (its
    seeding rule, for callers that need a model's joints) (:mod:`rockmass.blockgen.joints`).
:class:`Excavation`, :func:`circle`, :func:`horseshoe`, :func:`arched_cavern`, :func:`rectangle`,
:func:`polygon_excavation`, :func:`circle_perimeter_m`
    Excavation stages (:mod:`rockmass.blockgen.excavations`).
:func:`check_model`
    The invariants (area balance, no overlap, shared edges, convexity) (:mod:`rockmass.blockgen.checks`).
:func:`to_json_dict`, :func:`from_json_dict`, :func:`write_json`, :func:`read_json`, :func:`write_vtu`,
:func:`polygon_cells`
    Files, and the meshio cells of the blocks that the solver's frames reuse
    (:mod:`rockmass.blockgen.blockio`); :func:`plot_blocks` (:mod:`rockmass.blockgen.plots`).
:class:`BlockQuality`
    The quality report of a model, ``model.quality`` (:mod:`rockmass.blockgen.quality`).
:class:`Tolerances`, :func:`model_tolerances`
    Every tolerance with its reason (:mod:`rockmass.blockgen.tolerances`).

``rockmass.blockgen`` may import ``rockmass.dfn`` but never the pipeline modules.
"""

from .blockio import from_json_dict, polygon_cells, read_json, to_json_dict, write_json, write_vtu
from .builder import DANGLING_CHOICES, build
from .checks import check_model
from .cracks import CRACK_PATTERNS, Cracks
from .excavations import (DEFAULT_CIRCLE_SIDES, Excavation, arched_cavern, circle,
                          circle_perimeter_m, horseshoe, polygon_excavation, rectangle)
from .joints import SPACING_DISTRIBUTIONS, JointSet, joint_set_segments
from .model import CONTACT_KINDS, SOURCE_CONVEX_CUT, SOURCE_CRACK, BlockModel, polygon_properties
from .quality import BlockQuality
from .tolerances import Tolerances, model_tolerances

__all__ = ["build", "DANGLING_CHOICES", "BlockModel", "BlockQuality", "CONTACT_KINDS",
           "polygon_properties",
           "JointSet", "SPACING_DISTRIBUTIONS", "joint_set_segments", "Excavation", "circle",
           "horseshoe", "arched_cavern",
           "rectangle", "polygon_excavation", "circle_perimeter_m", "DEFAULT_CIRCLE_SIDES",
           "Tolerances", "model_tolerances", "check_model", "to_json_dict", "from_json_dict",
           "write_json", "read_json", "write_vtu", "polygon_cells", "plot_blocks", "Cracks",
           "CRACK_PATTERNS",
           "SOURCE_CONVEX_CUT", "SOURCE_CRACK"]


def __getattr__(name):  # matplotlib only when a plot is drawn
    if name == "plot_blocks":
        from .plots import plot_blocks

        return plot_blocks
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
