"""PhotoDEM — aerial photogrammetry for QGIS.

QGIS imports this folder as the package ``photodem`` and calls :func:`classFactory`. Nothing
else lives here, so ``import photodem.algorithms`` works without Qt or QGIS.
"""


def classFactory(iface):
    """Create the plugin; ``iface`` is ``None`` under ``qgis_process``."""
    from .plugin.qgis.plugin import PhotodemPlugin

    return PhotodemPlugin(iface)
