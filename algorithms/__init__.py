"""PhotoDEM core: pure Python photogrammetry (no Qt, no QGIS)."""

__version__ = "0.1.0"
