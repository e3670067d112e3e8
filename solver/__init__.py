"""The distinct element (DEM) core: rigid polygonal blocks on joint contacts.

Planned content (issue "The DEM core"). Nothing is public yet.
"""

__all__: list[str] = []
