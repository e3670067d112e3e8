"""``[blocks3d]``: a 3D block model (:class:`rockmass.blockgen.model3d.Blocks3DSettings`), strict and
range-checked. The section is the library type itself: every key, default, range and description
is declared once, there. Example::

    [blocks3d]
    box_min_m = [0.0, 0.0, 0.0]
    box_max_m = [20.0, 20.0, 20.0]
    dfn_realization = 0                 # cut by realization 0 of the [dfn] sets of this file

    [[blocks3d.sets]]                   # and/or persistent joint sets
    dip_deg = 10.0
    dip_direction_deg = 120.0
    spacing_m = 2.0

    [[blocks3d.tunnels]]
    shape = "horseshoe"
    centre_m = [10.0, 0.0, 7.0]
    width_m = 6.0
    wall_height_m = 3.0
"""

from __future__ import annotations

from .strict import library_section

__all__ = ["Blocks3DConfig"]


def _library():
    from .blockgen.model3d import Blocks3DSettings

    return Blocks3DSettings


Blocks3DConfig = library_section(_library())
