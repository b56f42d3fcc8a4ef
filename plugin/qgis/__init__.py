"""The QGIS face of PhotoDEM: plugin class, Processing provider, generic algorithm."""
