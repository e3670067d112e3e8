"""Face photographs to joint traces (polylines in metres on the face frame).

Planned content (issue "Traces from face photographs"): illumination flattening, multi-scale ridge
filtering, thresholding, skeleton graph, pruning and gap bridging, producing a
:class:`rockmass.dfn.TraceMap`. Nothing is public yet.
"""

__all__: list[str] = []
