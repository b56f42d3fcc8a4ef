"""The QGIS plugin class: Processing provider, Raster menu (with *Open project…*), toolbar button.

QGIS desktop calls ``classFactory(iface)`` then :meth:`PhotodemPlugin.initGui`; ``qgis_process``
calls ``classFactory(None)`` then only :meth:`PhotodemPlugin.initProcessing`. So
``initProcessing`` never touches ``iface``, ``initGui`` calls it, and :meth:`unload` undoes both.
"""

from __future__ import annotations

import importlib.util
from typing import Any, List, Optional

from qgis.core import Qgis, QgsApplication, QgsMessageLog
from qgis.PyQt.QtCore import Qt
from qgis.PyQt.QtWidgets import QDockWidget

from ...algorithms.processing import registry
from ..i18n import install_translator, remove_translator, tr
from ..qt import QAction, QIcon
from .project_menu import ProjectMenu
from .provider import ICON_PATH, PROVIDER_ID, PhotodemProvider
from .workspace import current_workspace, workspace_notifier

MENU_TITLE = "&PhotoDEM"
#: Python packages the core needs (import name → Debian package).
DEPENDENCIES = {
    "numpy": "python3-numpy",
    "scipy": "python3-scipy",
    "skimage": "python3-skimage",
    "rasterio": "python3-rasterio",
    "affine": "python3-affine",
    "fiona": "python3-fiona",
    "shapely": "python3-shapely",
    "pyproj": "python3-pyproj",
    "yaml": "python3-yaml",
}


def missing_dependencies() -> List[str]:
    """Import names of the core's dependencies that this QGIS Python cannot find."""
    return [name for name in DEPENDENCIES if importlib.util.find_spec(name) is None]


def dependency_message(missing: List[str]) -> str:
    """One operator-readable line: what is missing and how to install it."""
    debian = " ".join(DEPENDENCIES[m] for m in missing)
    return tr("PhotoDEM needs Python packages that QGIS cannot find: {0}. "
              "Debian/Ubuntu: sudo apt install {1}; Windows: install them with the OSGeo4W "
              "installer.").format(", ".join(missing), debian)


class PhotodemPlugin:
    """PhotoDEM inside QGIS.

    Parameters
    ----------
    iface : QgisInterface or None
        ``None`` under ``qgis_process``.
    """

    def __init__(self, iface: Any) -> None:
        self.iface = iface
        # References are kept on purpose: sip/GC would otherwise drop the provider, the
        # translator or the actions and the algorithms would silently vanish.
        self.provider: Optional[PhotodemProvider] = None
        self.actions: List[QAction] = []
        self.toolbox_action: Optional[QAction] = None
        self.editing_toolbar: Any = None  # the "PhotoDEM editing" toolbar
        self.model_actions: Any = None  # actions on stereo models (run from the map)
        self.project_menu: Optional[ProjectMenu] = None  # Open project… and recent projects
        self.translator = install_translator()
        self.missing = missing_dependencies()

    # -- Processing (desktop and qgis_process) --------------------------------------------------
    def initProcessing(self) -> None:
        """Register the provider ``photodem``; safe to call twice; never uses ``iface``.

        Without the core's dependencies no provider is registered; the reason goes to the QGIS
        message log (and to the message bar in :meth:`initGui`).
        """
        if self.missing:
            QgsMessageLog.logMessage(dependency_message(self.missing), "PhotoDEM", Qgis.Critical)
            return
        if self.provider is None:
            self.provider = PhotodemProvider()
            QgsApplication.processingRegistry().addProvider(self.provider)

    # -- desktop --------------------------------------------------------------------------------
    def initGui(self) -> None:
        """Provider, a PhotoDEM entry per algorithm in the Raster menu, a toolbar button."""
        self.initProcessing()
        if self.iface is None:
            return
        if self.missing:
            self.iface.messageBar().pushCritical("PhotoDEM", dependency_message(self.missing))
            return
        parent = self.iface.mainWindow()
        icon = QIcon(str(ICON_PATH))
        self._init_workspace()  # Open project… heads the menu
        self.toolbox_action = QAction(icon, tr("PhotoDEM algorithms"), parent)
        self.toolbox_action.setObjectName("photodemShowToolbox")
        self.toolbox_action.setToolTip(tr("Show the PhotoDEM algorithms in the Processing Toolbox"))
        self.toolbox_action.triggered.connect(self.show_toolbox)
        self.iface.addToolBarIcon(self.toolbox_action)
        self.iface.addPluginToRasterMenu(MENU_TITLE, self.toolbox_action)
        self.actions.append(self.toolbox_action)
        for spec in registry.algorithms().values():
            action = QAction(icon, tr(spec.name or spec.id) + "…", parent)
            action.setObjectName(f"photodem_{spec.id}")
            action.triggered.connect(lambda _checked=False, i=spec.id: self.open_dialog(i))
            self.iface.addPluginToRasterMenu(MENU_TITLE, action)
            self.actions.append(action)
        review = QAction(icon, tr("Review georeferencing…"), parent)
        review.setObjectName("photodemGeorefReview")
        review.setToolTip(tr("Check and edit the control points of a georeferencing result"))
        review.triggered.connect(lambda _checked=False: self.open_georef_review())
        self.iface.addPluginToRasterMenu(MENU_TITLE, review)
        self.actions.append(review)
        # lazy: the batch dialog (Qt widgets, QgsTask) exists only in the desktop application
        from .batch_actions import BatchMenu

        self.batch_menu = BatchMenu(self.iface, MENU_TITLE, icon)  # Batch over stereo models…
        self.batch_menu.register()
        # issue 20: the DEM quality dock (made on first use)
        quality = QAction(icon, tr("DEM quality…"), parent)
        quality.setObjectName("photodemQualityDock")
        quality.setToolTip(tr("Statistics of an area, histogram, profiles, identify and "
                              "blunders of a DEM against a reference"))
        quality.triggered.connect(lambda _checked=False: self.show_quality_dock())
        self.iface.addPluginToRasterMenu(MENU_TITLE, quality)
        self.actions.append(quality)

    def _init_workspace(self) -> None:
        """The project workspace: Open project… and recent projects, the editing toolbar
        (disabled until a project is open) and the actions on stereo models."""
        # lazy: map tools, map-layer actions and dialogs exist only in the desktop application
        from .editing_toolbar import EditingToolbar
        from .model_actions import ModelActions

        self.project_menu = ProjectMenu(self.iface, MENU_TITLE)
        self.project_menu.register()
        self.editing_toolbar = EditingToolbar(self.iface)
        self.model_actions = ModelActions(self.iface)
        self.model_actions.register()
        workspace_notifier().changed.connect(self.workspace_changed)
        self.workspace_changed(current_workspace())  # a .qgz read before the plugin loaded

    def open_project(self, path: Optional[str] = None) -> Any:
        """Open a PhotoDEM project as the workspace (asks for it without ``path``)."""
        return self.project_menu.open_project(path) if self.project_menu is not None else None

    def workspace_changed(self, workspace: Any) -> None:
        """A project was opened or closed: the editing toolbar works on it."""
        toolbar = getattr(self, "editing_toolbar", None)
        if toolbar is not None:
            toolbar.set_workspace(workspace)
        dock = getattr(self, "qc_dock", None)
        if dock is not None:  # the quality dock's defaults follow the project
            dock.set_workspace(workspace)

    def open_georef_review(self, folder: Optional[str] = None) -> Any:
        """Open the review dialog of a ``georeference_polygons`` output folder (asks for
        the folder unless given); returns the dialog or ``None``."""
        # lazy: the review dialog loads matplotlib and the georef package; opened on demand
        from ..widgets.georef_review import open_review

        def report(text: str) -> None:
            if self.iface is not None:
                self.iface.messageBar().pushWarning("PhotoDEM", text)

        parent = self.iface.mainWindow() if self.iface is not None else None
        dialog = open_review(parent, folder, on_error=report)
        if dialog is not None:
            self._review = dialog  # keep a reference while it is open
        return dialog

    def show_quality_dock(self) -> Any:
        """Show the DEM quality dock (issue 20), made on first use; returns it."""
        dock = getattr(self, "qc_dock", None)
        if dock is None:
            from .qc_dock import QcDock  # lazy: matplotlib and the map tools load on first use

            dock = self.qc_dock = QcDock(self.iface, self.iface.mainWindow())
            self.iface.addDockWidget(Qt.RightDockWidgetArea, dock)
        dock.set_workspace(current_workspace())
        dock.show()
        dock.raise_()
        return dock

    def open_dialog(self, algorithm_id: str) -> None:
        """Open the Processing dialog of ``photodem:<algorithm_id>``."""
        # lazy: QGIS's processing plugin exists only in the desktop application
        import processing

        processing.execAlgorithmDialog(f"{PROVIDER_ID}:{algorithm_id}")

    def show_toolbox(self) -> None:
        """Show the Processing Toolbox filtered to PhotoDEM (best effort; UI only)."""
        dock = self.iface.mainWindow().findChild(QDockWidget, "ProcessingToolbox")
        if dock is None:
            return
        dock.setVisible(True)
        dock.raise_()
        search = getattr(dock, "searchBox", None)
        if search is not None:
            search.setText("photodem")

    def unload(self) -> None:
        """Remove the menu entries, the toolbar button, the provider and the translator."""
        if getattr(self, "batch_menu", None) is not None:  # cancels a batch still running
            self.batch_menu.unregister()
            self.batch_menu = None
        if getattr(self, "qc_dock", None) is not None:  # issue 20: the DEM quality dock
            self.iface.removeDockWidget(self.qc_dock)
            self.qc_dock.deleteLater()
            self.qc_dock = None
        if self.editing_toolbar is not None:
            self.editing_toolbar.unload()
            self.editing_toolbar = None
        if self.model_actions is not None:
            self.model_actions.unregister()
            self.model_actions = None
        if self.project_menu is not None:
            workspace_notifier().changed.disconnect(self.workspace_changed)
            self.project_menu.unregister()
            self.project_menu = None
        if self.iface is not None:
            for action in self.actions:
                self.iface.removePluginRasterMenu(MENU_TITLE, action)
            if self.toolbox_action is not None:
                self.iface.removeToolBarIcon(self.toolbox_action)
        for action in self.actions:
            action.deleteLater()
        self.actions = []
        self.toolbox_action = None
        if self.provider is not None:
            QgsApplication.processingRegistry().removeProvider(self.provider)
            self.provider = None
        remove_translator()
        self.translator = None
