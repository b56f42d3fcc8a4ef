"""The map half of the standalone main window: the map view, its layers, a project on it.

:class:`MapWindowMixin` is mixed into :class:`~.main_window.ToolboxWindow` (a QMainWindow): it
builds the central :class:`~..widgets.map_view.MapView`, the *Layers* dock, the status bar
fields (coordinates, value under the cursor, scale, CRS), the File and View menu entries of the
map, and opens a project as QGIS's workspace does: edit layers, footprints and stereo models,
then the products — all styled from the same QML files.

Attributes the editing docks of part T use: ``map_view``, ``layer_list``, ``edit_session``
(an :class:`~..widgets.edit_session.EditSession` or None), ``project_root`` (Path or None) and
the window's signal ``project_opened(str root)``.
"""

from __future__ import annotations

import logging
import warnings
from pathlib import Path
from typing import Any, Iterable, List, Optional

from ...algorithms.errors import InputError
from ..i18n import error_text, tr
from ..qt import QtCore, QtGui, QtWidgets
from ..widgets.map_layer import MapLayer
from ..widgets.map_layers import LayerList
from ..widgets.map_view import MapView, MixedCoordinatesError
from ..widgets.run_panel import RASTER_SUFFIXES, VECTOR_SUFFIXES, is_map_file

LOG = logging.getLogger(__name__)

#: Settings key of the folder the file dialogs start in.
SETTINGS_MAP_DIR = "PhotoDEM/map/last_dir"
#: Raster files of a synthetic project's truth folder that are products when classified.
TRUTH_DIR = "truth"


class MapWindowMixin:
    """Map view, layer dock, status fields and project opening of the main window."""

    map_view: MapView
    layer_list: LayerList
    edit_session: Any
    project_root: Optional[Path]
    project: Any
    message_boxes: bool
    settings: Any

    # -- building --------------------------------------------------------------------------------
    def _build_map(self) -> None:
        """The central map, the *Layers* dock and the status bar fields."""
        window: QtWidgets.QMainWindow = self  # type: ignore[assignment]
        self.edit_session = None
        self.project_root = None
        self.project = None
        self.map_view = MapView(window)
        self.map_view.setObjectName("photodemMap")
        window.setCentralWidget(self.map_view)
        self.layer_list = LayerList(self.map_view)
        self.layer_list.message.connect(lambda text: self.report(text, warning=False))
        dock = QtWidgets.QDockWidget(tr("Layers"), window)
        dock.setObjectName("photodemLayers")
        dock.setWidget(self.layer_list)
        window.addDockWidget(QtCore.Qt.LeftDockWidgetArea, dock)
        self.layers_dock = dock

        bar = window.statusBar()
        self.coord_label = self._status_label(tr("Coordinates of the cursor"), 190)
        self.value_label = self._status_label(tr("Value of the top raster under the cursor"),
                                              170)
        self.scale_label = self._status_label(tr("Scale at 96 dpi"), 90)
        self.crs_label = self._status_label(tr("Coordinate reference system of the map"), 90)
        for label in (self.coord_label, self.value_label, self.scale_label, self.crs_label):
            bar.addPermanentWidget(label)
        self.map_view.cursor_moved.connect(self._on_cursor)
        self.map_view.extent_changed.connect(self._update_scale)
        self._update_scale()

    def _status_label(self, tip: str, width: int) -> QtWidgets.QLabel:
        label = QtWidgets.QLabel()
        label.setToolTip(tip)
        label.setMinimumWidth(width)
        label.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        return label

    def _build_map_menus(self, file_menu: QtWidgets.QMenu, view_menu: QtWidgets.QMenu) -> None:
        """File: open a project, add a raster or vector; View: zooms."""
        style = self.style()  # type: ignore[attr-defined]
        self.open_project_action = file_menu.addAction(
            style.standardIcon(QtWidgets.QStyle.SP_DirOpenIcon), tr("&Open project…"))
        self.open_project_action.setShortcut(QtGui.QKeySequence.Open)
        self.open_project_action.triggered.connect(lambda _c=False: self.choose_project())
        self.add_raster_action = file_menu.addAction(tr("Add &raster…"))
        self.add_raster_action.triggered.connect(lambda _c=False: self.choose_map_file(True))
        self.add_vector_action = file_menu.addAction(tr("Add &vector…"))
        self.add_vector_action.triggered.connect(lambda _c=False: self.choose_map_file(False))
        file_menu.addSeparator()
        view = self.map_view
        self.zoom_full_action = view_menu.addAction(tr("Zoom &full"))
        self.zoom_full_action.setShortcut(QtGui.QKeySequence("Ctrl+Shift+F"))
        self.zoom_full_action.triggered.connect(lambda _c=False: view.zoom_full())
        self.zoom_layer_action = view_menu.addAction(tr("Zoom to &layer"))
        self.zoom_layer_action.triggered.connect(lambda _c=False: self.layer_list.zoom_to_current())
        self.zoom_in_action = view_menu.addAction(tr("Zoom &in"))
        self.zoom_in_action.setShortcut(QtGui.QKeySequence.ZoomIn)
        self.zoom_in_action.triggered.connect(lambda _c=False: view.zoom_by(2.0))
        self.zoom_out_action = view_menu.addAction(tr("Zoom &out"))
        self.zoom_out_action.setShortcut(QtGui.QKeySequence.ZoomOut)
        self.zoom_out_action.triggered.connect(lambda _c=False: view.zoom_by(0.5))
        view_menu.addSeparator()
        self._build_map_toolbar()

    def _build_map_toolbar(self) -> None:
        """Open project and the zooms one click away (the editing toolbar comes below)."""
        window: QtWidgets.QMainWindow = self  # type: ignore[assignment]
        style = window.style()
        bar = QtWidgets.QToolBar(tr("Map"), window)
        bar.setObjectName("photodemMapToolbar")
        icons = ((self.open_project_action, QtWidgets.QStyle.SP_DirOpenIcon),
                 (self.zoom_full_action, QtWidgets.QStyle.SP_DesktopIcon),
                 (self.zoom_layer_action, QtWidgets.QStyle.SP_FileDialogContentsView),
                 (self.zoom_in_action, QtWidgets.QStyle.SP_ArrowUp),
                 (self.zoom_out_action, QtWidgets.QStyle.SP_ArrowDown))
        for action, icon in icons:
            action.setIcon(style.standardIcon(icon))
            bar.addAction(action)
        bar.setToolButtonStyle(QtCore.Qt.ToolButtonTextBesideIcon)
        window.addToolBar(bar)
        self.map_toolbar = bar

    # -- status bar ------------------------------------------------------------------------------
    def _on_cursor(self, x: float, y: float) -> None:
        if self.map_view.is_georeferenced():
            self.coord_label.setText(f"{x:.2f}, {y:.2f} m")
        else:
            self.coord_label.setText(tr("pixel {0:.1f}, {1:.1f}").format(x, -y))
        self.value_label.setText(self.value_under(x, y) or "")

    def value_under(self, x: float, y: float) -> Optional[str]:
        """The value of the topmost visible raster at the map point (or of the top vector
        feature there when no raster has a value)."""
        vector_text = None
        for layer in self.map_view.layers():
            if not layer.visible:
                continue
            is_raster = hasattr(layer, "sample")
            if not is_raster and vector_text is not None:
                continue
            try:
                text = layer.value_at(x, y)
            except Exception:  # a broken file must not break the status bar
                LOG.exception("value of %s", layer.name)
                text = None
            if text and is_raster:
                return text
            vector_text = vector_text or text
        return vector_text

    def _update_scale(self) -> None:
        view = self.map_view
        if view.is_georeferenced():
            self.scale_label.setText(f"1:{round(view.scale()):,}".replace(",", " "))
        else:
            self.scale_label.setText(tr("pixels"))
        self.crs_label.setText(_crs_name(view.crs()) or tr("no CRS"))

    def report(self, text: str, warning: bool = True) -> None:
        """Tell the operator: status bar, and a message box when they are switched on."""
        window: QtWidgets.QMainWindow = self  # type: ignore[assignment]
        window.statusBar().showMessage(text, 15000)
        if warning and self.message_boxes:
            QtWidgets.QMessageBox.warning(window, tr("PhotoDEM"), text)

    # -- adding layers ---------------------------------------------------------------------------
    def add_raster_file(self, path: Any, kind: str = "auto", name: str = "",
                        index: Optional[int] = None) -> Optional[MapLayer]:
        """Add a raster; a raster without CRS is shown alone, in pixel coordinates, with a
        warning; a file GDAL can't open gives a message, not a traceback."""
        view = self.map_view
        georeferenced_view = view.is_georeferenced() and bool(view.layers())
        try:
            layer = view.add_raster(path, kind=kind, name=name)
        except MixedCoordinatesError as exc:
            return self._raster_alone_or_with_map(path, kind, name, georeferenced_view, exc)
        except InputError as exc:  # GDAL can't open it: the message names the file
            self.report(error_text(exc))
            return None
        except Exception as exc:  # GDAL/rasterio errors of a broken file
            LOG.exception("raster %s", path)
            self.report(tr("Cannot show '{0}': {1}").format(Path(path).name, exc))
            return None
        if index is not None:
            view.move_layer(layer, index)
        self._offer_overviews(layer)
        if not layer.has_crs:  # type: ignore[attr-defined]
            self.report(tr("'{0}' has no coordinate reference system: it is shown in pixel "
                           "coordinates.").format(Path(path).name))
        return layer

    def _offer_overviews(self, layer: MapLayer) -> None:
        """A big raster without overviews draws slowly: say how to build them."""
        if getattr(layer, "needs_overviews", False):
            window: QtWidgets.QMainWindow = self  # type: ignore[assignment]
            window.statusBar().showMessage(
                tr("{0} has no overviews and draws slowly: right-click it in the layer list "
                   "→ Build overviews.").format(layer.name), 20000)

    def _raster_alone_or_with_map(self, path: Any, kind: str, name: str,
                                  georeferenced_view: bool, exc: Exception) -> Optional[MapLayer]:
        """The raster could not join the view: without CRS it is shown alone (warning); a
        georeferenced raster replaces a pixel-coordinate view."""
        view = self.map_view
        if georeferenced_view:  # the raster has no CRS
            view.clear_layers()
            view.set_crs("")
        else:  # the view shows a raster without CRS: back to map coordinates
            self._ensure_georeferenced()
        try:
            layer = view.add_raster(path, kind=kind, name=name)
        except InputError:
            self.report(error_text(exc))
            return None
        view.zoom_to_layer(layer)
        if georeferenced_view:
            self.report(tr("'{0}' has no coordinate reference system: it is shown alone, in "
                           "pixel coordinates.").format(Path(path).name))
        return layer

    def add_vector_file(self, source: Any, kind: str = "vector", name: str = "",
                        layer: Optional[str] = None) -> Optional[MapLayer]:
        """Add a vector file (or callable); messages instead of tracebacks."""
        try:
            return self.map_view.add_vector(source, kind, name=name, layer=layer)
        except Exception as exc:  # fiona/GDAL errors, or pixel/map coordinates mixed
            LOG.info("vector %s not added: %s", source, exc)
            self.report(str(exc) if isinstance(exc, InputError)
                        else tr("Cannot show '{0}': {1}").format(source, exc))
            return None

    def _ensure_georeferenced(self) -> None:
        """A pixel-coordinate view (a raster without CRS shown alone) gives way to a map in
        the project's CRS when a georeferenced layer is added."""
        view = self.map_view
        if not view.is_georeferenced() and view.layers():
            view.clear_layers()
            if self.project is not None and getattr(self.project, "crs", ""):
                view.set_crs(str(self.project.crs))

    def add_map_file(self, path: Any) -> Optional[MapLayer]:
        """Add a raster or vector file by its ending (kind from the product it is)."""
        # lazy: the product classifier is only needed for files added by hand
        from ...algorithms.project.products import classify

        path = Path(path)
        product = classify(path)
        name = product_label(product) if product is not None else ""
        if path.suffix.lower() in RASTER_SUFFIXES:
            return self.add_raster_file(path, kind=product.kind if product else "auto",
                                        name=name)
        self._ensure_georeferenced()
        if product is not None and product.kind == "seamlines":
            return self.add_vector_file(path, "seamlines", name=name, layer="seamlines")
        return self.add_vector_file(path, "vector")

    def show_on_map(self, path: str) -> Optional[MapLayer]:
        """Show the output ``path``: added if absent, made visible, zoomed to."""
        layer = self.map_view.layer_by_path(path)
        if layer is None:
            layer = self.add_map_file(path)
        if layer is None:
            return None
        layer.visible = True
        self.map_view.zoom_to_layer(layer)
        self.layer_list.select_layer(layer)
        return layer

    def add_run_outputs(self, paths: Iterable[str]) -> List[MapLayer]:
        """Add the raster and vector outputs of a finished run that are not on the map yet."""
        was_empty = not self.map_view.layers()
        added, apart = [], []
        for path in paths:
            if is_map_file(path) and self.map_view.layer_by_path(path) is None:
                if self._would_replace_the_map(path):  # an epipolar image: the map stays
                    apart.append(Path(path).name)
                    continue
                layer = self.add_map_file(path)
                if layer is not None:
                    added.append(layer)
        if added and was_empty:
            self.map_view.zoom_full()
        if apart:
            window: QtWidgets.QMainWindow = self  # type: ignore[assignment]
            window.statusBar().showMessage(
                tr("Not added to the map (no coordinate reference system): {0}. Show on map "
                   "in the run panel shows one alone.").format(", ".join(apart)), 20000)
        return added

    def _would_replace_the_map(self, path: Any) -> bool:
        """True for a raster without CRS while the map shows georeferenced layers: adding
        it would take the project off the map (the two never mix)."""
        view = self.map_view
        if Path(path).suffix.lower() not in RASTER_SUFFIXES or not view.layers() \
                or not view.is_georeferenced():
            return False
        try:
            # lazy: rasterio opens the file only to read its CRS
            import rasterio

            with warnings.catch_warnings():  # "not georeferenced" is what we ask about
                warnings.simplefilter("ignore")
                with rasterio.open(path) as src:
                    return src.crs is None
        except Exception:  # unreadable: add_map_file reports it
            return False

    # -- dialogs ---------------------------------------------------------------------------------
    def _last_dir(self) -> str:
        if self.project_root is not None:
            return str(self.project_root)
        return str(self.settings.value(SETTINGS_MAP_DIR, "")) if self.settings else ""

    def choose_project(self) -> bool:
        """Ask for a project folder and open it."""
        folder = QtWidgets.QFileDialog.getExistingDirectory(
            self, tr("Open PhotoDEM project"), self._last_dir())  # type: ignore[arg-type]
        return bool(folder) and self.open_project(folder)

    def choose_map_file(self, raster: bool) -> Optional[MapLayer]:
        """Ask for a raster (or vector) file and add it to the map."""
        if raster:
            pattern = tr("Rasters") + " (" + " ".join(f"*{s}" for s in RASTER_SUFFIXES) + ")"
        else:
            pattern = tr("Vectors") + " (" + " ".join(f"*{s}" for s in VECTOR_SUFFIXES) + ")"
        path, _ = QtWidgets.QFileDialog.getOpenFileName(
            self, tr("Add raster") if raster else tr("Add vector"),  # type: ignore[arg-type]
            self._last_dir(), pattern + ";;" + tr("All files") + " (*)")
        if not path:
            return None
        if self.settings is not None:
            self.settings.setValue(SETTINGS_MAP_DIR, str(Path(path).parent))
        layer = self.add_map_file(path)
        if layer is not None and len(self.map_view.layers()) == 1:
            self.map_view.zoom_to_layer(layer)
        return layer

    # -- projects --------------------------------------------------------------------------------
    def close_project(self) -> bool:
        """Ask about unsaved edits and take the project off the map; False when cancelled."""
        session = self.edit_session
        if session is not None and not session.maybe_save(self):
            return False
        self.map_view.set_tool(None)
        self.map_view.clear_layers()
        if session is not None:
            session.deleteLater()
        self.edit_session = None
        self.project_root = None
        self.project = None
        return True

    def open_project(self, path: Any) -> bool:
        """Show the project ``path`` (its folder or ``project.toml``) as QGIS's workspace
        does: edit layers, footprints and stereo models, products; zoom to the block.

        Returns False (with a message) for a folder that is no project or when the operator
        cancels the question about unsaved edits; emits ``project_opened(root)`` otherwise.
        """
        # lazy: the project model loads with the first project
        from ...algorithms.project.model import Project

        try:
            project = Project.load(path)
        except InputError as exc:
            self.report(error_text(exc))
            return False
        if not self.close_project():
            return False
        root = project.project_file.parent.resolve()
        self.project, self.project_root = project, root
        self.map_view.set_crs(str(project.crs or ""))
        problems: List[str] = []
        self._add_products(root, problems)
        self._add_block(project, problems)
        self._add_edits(root, problems)
        block = self.map_view.layer_by_kind("footprints")
        if block is not None and block.bounds() is not None:
            self.map_view.zoom_to_layer(block)
        else:
            self.map_view.zoom_full()
        if self.settings is not None:
            self.settings.setValue(SETTINGS_MAP_DIR, str(root))
        window: QtWidgets.QMainWindow = self  # type: ignore[assignment]
        window.setWindowTitle(tr("PhotoDEM – {0}").format(root.name))
        if problems:
            self.report("\n".join(problems))
        else:
            window.statusBar().showMessage(tr("Project {0} opened.").format(root), 10000)
        self.project_opened.emit(str(root))  # type: ignore[attr-defined]
        return True

    def _add_products(self, root: Path, problems: List[str]) -> None:
        """The products (found by their place in the folder, so a moved project still opens)
        and the classified truth rasters of a synthetic project (below the products)."""
        # lazy: product discovery walks the project folder only when one is opened
        from ...algorithms.project.products import classify, find_products

        products = find_products(root)
        truth = root / TRUTH_DIR
        if truth.is_dir():
            products += [p for p in (classify(f) for f in sorted(truth.glob("*.tif")))
                         if p is not None and p.kind != "seamlines"]
        # vectors (seamlines) above the rasters; otherwise find_products' order, top first
        products.sort(key=lambda p: p.kind != "seamlines")
        for product in reversed(products):
            if product.kind == "seamlines":
                layer = self.add_vector_file(product.path, "seamlines",
                                             name=product_label(product), layer="seamlines")
            else:
                layer = self.add_raster_file(product.path, kind=product.kind,
                                             name=product_label(product))
            if layer is None:
                problems.append(tr("Product not shown: {0}").format(product.path))
            else:
                self._offer_overviews(layer)

    def _add_block(self, project: Any, problems: List[str]) -> None:
        """Footprints and stereo models from ``.photodem/block.gpkg`` (written when stale)."""
        # lazy: the block layers need fiona and the camera model
        from ...algorithms.project.block_layers import write_block_layers

        try:
            block = write_block_layers(project)
        except Exception as exc:  # no CRS, no cameras, read-only folder
            problems.append(tr("Footprints and stereo models not shown: {0}").format(exc))
            return
        # stereo models above the footprints, as in QGIS
        self.add_vector_file(block, "footprints", name=tr("Image footprints"),
                             layer="footprints")
        self.add_vector_file(block, "stereo_models", name=tr("Stereo models"),
                             layer="stereo_models")

    def _add_edits(self, root: Path, problems: List[str]) -> None:
        """The edit layers of the project's edit session (read-only for a bad file), drawn
        from its memory and redrawn on its changes."""
        # lazy: the edit session loads edits.gpkg only when a project is opened
        from ..widgets.edit_session import EditSession, show_edits

        session = EditSession(root, parent=self, crs=str(getattr(self.project, "crs", "")))
        self.edit_session = session
        if session.read_only:
            problems.append(session.problem)
        show_edits(self.map_view, session)


def product_label(product: Any) -> str:
    """The layer name of a product: ``DSM 0101_0102``, ``Ortho 0203`` (as in QGIS)."""
    names = {"dsm": tr("DSM"), "dtm": tr("DTM"), "difference": tr("Difference"),
             "ortho": tr("Ortho"), "mosaic": tr("Mosaic"), "seamlines": tr("Seamlines")}
    kind = names.get(product.kind, product.kind)
    return kind if product.name.lower() == product.kind else f"{kind} {product.name}"


def _crs_name(crs: str) -> str:
    """A short name of a CRS (``EPSG:25832``) for the status bar."""
    if not crs:
        return ""
    if crs.upper().startswith("EPSG:"):
        return crs.upper()
    try:
        # lazy: pyproj parses a WKT only for the status bar
        from pyproj import CRS

        parsed = CRS.from_user_input(crs)
        code = parsed.to_epsg()
        return f"EPSG:{code}" if code else parsed.name
    except Exception:  # an odd WKT: show its start
        return crs[:24]


__all__ = ["MapWindowMixin", "product_label"]
