"""Block models: a 2D section cut by joint sets or DFN traces, with excavations.

Planned content (issue "Block models"): ``BlockModel`` and ``build``. Nothing is public yet.
"""

__all__: list[str] = []
