"""The Processing provider ``photodem``: one algorithm per registry spec."""

from __future__ import annotations

from pathlib import Path

from qgis.core import QgsProcessingProvider

from ...algorithms import __version__
from ...algorithms.processing import registry
from ..i18n import tr
from ..qt import QIcon
from .algorithm import PhotodemAlgorithm

PROVIDER_ID = "photodem"
#: The plugin icon, loaded by path (no Qt resource file to compile).
ICON_PATH = Path(__file__).resolve().parents[2] / "resources" / "icons" / "photodem.svg"


class PhotodemProvider(QgsProcessingProvider):
    """Processing provider listing every algorithm of the PhotoDEM registry as ``photodem:<id>``."""

    def __init__(self) -> None:
        super().__init__()
        self._icon = QIcon(str(ICON_PATH))

    def id(self) -> str:
        return PROVIDER_ID

    def name(self) -> str:
        return "PhotoDEM"

    def longName(self) -> str:
        return tr("PhotoDEM aerial photogrammetry") + f" {__version__}"

    def versionInfo(self) -> str:  # noqa: N802 (QGIS API)
        return __version__

    def icon(self) -> QIcon:
        return self._icon

    def svgIconPath(self) -> str:  # noqa: N802 (QGIS API)
        return str(ICON_PATH)

    def defaultRasterFileExtension(self) -> str:  # noqa: N802 (QGIS API)
        return "tif"

    def defaultVectorFileExtension(self, hasGeometry: bool = True) -> str:  # noqa: N802
        return "gpkg"

    def supportsNonFileBasedOutput(self) -> bool:  # noqa: N802 (QGIS API)
        return False  # the core writes files with rasterio/fiona, never memory layers

    def loadAlgorithms(self) -> None:
        for spec in registry.algorithms().values():
            self.addAlgorithm(PhotodemAlgorithm(spec, self._icon))
