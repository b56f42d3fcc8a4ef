"""The layer list of the standalone map: visibility, order, opacity, zoom, remove.

:class:`LayerList` mirrors a :class:`~.map_view.MapView`'s layers (top first, as in QGIS's
layer panel): a check box per layer switches it on and off, drag and drop or the arrow buttons
change the order, the slider sets the selected layer's opacity; *Zoom to layer* and *Remove*
are buttons and context-menu entries.
"""

from __future__ import annotations

import contextlib
from typing import List, Optional

from ..i18n import tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal
from .map_layer import MapLayer
from .map_view import MapView

#: Item role holding the position of the item's layer in ``LayerList._layers``.
LAYER_ROLE = QtCore.Qt.UserRole + 11
#: Swatch colours of raster kinds in the list (vectors show their style's colour).
_KIND_COLOURS = {"dsm": "#b07d48", "dtm": "#7a9a4a", "difference": "#c0392b",
                 "ortho": "#6b8fb3", "mosaic": "#6b8fb3", "image": "#888888"}


def layer_swatch(layer: MapLayer, size: int = 14) -> QtGui.QIcon:
    """A small square in the layer's colour (its vector style or its raster kind)."""
    pixmap = QtGui.QPixmap(size, size)
    pixmap.fill(QtCore.Qt.transparent)
    painter = QtGui.QPainter(pixmap)
    style = getattr(layer, "style", None)
    if style is not None and hasattr(style, "symbol"):
        symbol = style.symbol
        colour = QtGui.QColor(*symbol.pen)
        fill = QtGui.QColor(*(symbol.brush if symbol.brush[3] else symbol.marker_fill))
        if fill.alpha() < 60:
            fill.setAlpha(60)
    else:
        colour = QtGui.QColor(_KIND_COLOURS.get(layer.kind, "#999999"))
        fill = QtGui.QColor(colour).lighter(130)
    painter.setPen(QtGui.QPen(colour, 2))
    painter.setBrush(fill)
    painter.drawRect(QtCore.QRectF(2, 2, size - 4, size - 4))
    painter.end()
    return QtGui.QIcon(pixmap)


class LayerList(QtWidgets.QWidget):
    """A layer panel bound to a :class:`MapView`.

    Signals
    -------
    current_layer_changed(object)
        The selected layer (or None).
    message(str)
        Something the operator should read (an error of *Build overviews*).
    """

    current_layer_changed = pyqtSignal(object)
    message = pyqtSignal(str)

    def __init__(self, view: MapView, parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self.view = view
        self._layers: List[MapLayer] = []
        self._syncing = False

        self.list = QtWidgets.QListWidget(self)
        self.list.setDragDropMode(QtWidgets.QAbstractItemView.InternalMove)
        self.list.setDefaultDropAction(QtCore.Qt.MoveAction)
        self.list.setSelectionMode(QtWidgets.QAbstractItemView.SingleSelection)
        self.list.setContextMenuPolicy(QtCore.Qt.CustomContextMenu)
        self.list.setIconSize(QtCore.QSize(14, 14))
        self.opacity_slider = QtWidgets.QSlider(QtCore.Qt.Horizontal, self)
        self.opacity_slider.setRange(0, 100)
        self.opacity_slider.setValue(100)
        self.opacity_slider.setToolTip(tr("Opacity of the selected layer"))
        self.opacity_label = QtWidgets.QLabel(tr("Opacity"), self)
        self.up_button = self._button(QtWidgets.QStyle.SP_ArrowUp, tr("Move the layer up"))
        self.down_button = self._button(QtWidgets.QStyle.SP_ArrowDown,
                                        tr("Move the layer down"))
        self.zoom_button = self._button(QtWidgets.QStyle.SP_FileDialogContentsView,
                                        tr("Zoom to layer"))
        self.remove_button = self._button(QtWidgets.QStyle.SP_TrashIcon, tr("Remove layer"))

        buttons = QtWidgets.QHBoxLayout()
        for button in (self.up_button, self.down_button, self.zoom_button, self.remove_button):
            buttons.addWidget(button)
        buttons.addStretch(1)
        opacity = QtWidgets.QHBoxLayout()
        opacity.addWidget(self.opacity_label)
        opacity.addWidget(self.opacity_slider, 1)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addWidget(self.list, 1)
        layout.addLayout(opacity)
        layout.addLayout(buttons)

        self.up_button.clicked.connect(lambda _c=False: self.move_current(-1))
        self.down_button.clicked.connect(lambda _c=False: self.move_current(1))
        self.zoom_button.clicked.connect(lambda _c=False: self.zoom_to_current())
        self.remove_button.clicked.connect(lambda _c=False: self.remove_current())
        self.opacity_slider.valueChanged.connect(self._on_opacity)
        self.list.itemChanged.connect(self._on_item_changed)
        self.list.currentRowChanged.connect(self._on_current_row)
        self.list.model().rowsMoved.connect(self._on_rows_moved)
        self.list.customContextMenuRequested.connect(self._context_menu)
        view.layers_changed.connect(self.sync)
        self.sync()

    def _button(self, icon: QtWidgets.QStyle.StandardPixmap, tip: str) -> QtWidgets.QToolButton:
        button = QtWidgets.QToolButton(self)
        button.setIcon(self.style().standardIcon(icon))
        button.setToolTip(tip)
        button.setAutoRaise(True)
        return button

    # -- mirror the view -------------------------------------------------------------------------
    def sync(self) -> None:
        """Show the view's layers again (after an add, remove or reorder)."""
        current = self.current_layer()
        for layer in self._layers:
            _disconnect(layer.changed, self._on_layer_changed)
        self._layers = self.view.layers()
        self._syncing = True
        self.list.clear()
        for i, layer in enumerate(self._layers):
            item = QtWidgets.QListWidgetItem(layer_swatch(layer), layer.name)
            item.setData(LAYER_ROLE, i)
            item.setFlags(item.flags() | QtCore.Qt.ItemIsUserCheckable
                          | QtCore.Qt.ItemIsDragEnabled)
            item.setFlags(item.flags() & ~QtCore.Qt.ItemIsDropEnabled)
            item.setCheckState(QtCore.Qt.Checked if layer.visible else QtCore.Qt.Unchecked)
            tip = layer.kind if layer.path is None else f"{layer.kind}: {layer.path}"
            item.setToolTip(tip)
            self.list.addItem(item)
            layer.changed.connect(self._on_layer_changed)
        self._syncing = False
        if current in self._layers:
            self.list.setCurrentRow(self._layers.index(current))
        self._update_controls()

    def _on_layer_changed(self) -> None:
        """A layer's visibility may have changed elsewhere: mirror the check boxes."""
        self._syncing = True
        for row in range(self.list.count()):
            item = self.list.item(row)
            layer = self._layers[item.data(LAYER_ROLE)]
            state = QtCore.Qt.Checked if layer.visible else QtCore.Qt.Unchecked
            if item.checkState() != state:
                item.setCheckState(state)
        self._syncing = False

    def layer_of_row(self, row: int) -> Optional[MapLayer]:
        """The layer shown in ``row``."""
        item = self.list.item(row)
        return None if item is None else self._layers[item.data(LAYER_ROLE)]

    def current_layer(self) -> Optional[MapLayer]:
        """The selected layer, or None."""
        return self.layer_of_row(self.list.currentRow()) if self._layers else None

    def select_layer(self, layer: MapLayer) -> None:
        """Select ``layer`` in the list."""
        for row in range(self.list.count()):
            if self.layer_of_row(row) is layer:
                self.list.setCurrentRow(row)
                return

    # -- user actions ----------------------------------------------------------------------------
    def _on_item_changed(self, item: QtWidgets.QListWidgetItem) -> None:
        if self._syncing:
            return
        layer = self._layers[item.data(LAYER_ROLE)]
        layer.visible = item.checkState() == QtCore.Qt.Checked

    def _on_current_row(self, _row: int) -> None:
        self._update_controls()
        self.current_layer_changed.emit(self.current_layer())

    def _update_controls(self) -> None:
        layer = self.current_layer()
        row = self.list.currentRow()
        for widget in (self.opacity_slider, self.zoom_button, self.remove_button):
            widget.setEnabled(layer is not None)
        self.up_button.setEnabled(layer is not None and row > 0)
        self.down_button.setEnabled(layer is not None and row < self.list.count() - 1)
        if layer is not None:
            self.opacity_slider.blockSignals(True)
            self.opacity_slider.setValue(round(layer.opacity * 100))
            self.opacity_slider.blockSignals(False)

    def _on_opacity(self, value: int) -> None:
        layer = self.current_layer()
        if layer is not None:
            layer.opacity = value / 100.0

    def _on_rows_moved(self, *_args: object) -> None:
        """Drag and drop reordered the items: the view follows."""
        if self._syncing:
            return
        order = [self.layer_of_row(row) for row in range(self.list.count())]
        QtCore.QTimer.singleShot(0, lambda: self._apply_order(order))

    def _apply_order(self, order: List[Optional[MapLayer]]) -> None:
        for index, layer in enumerate(order):
            if layer is not None and layer in self.view.layers():
                self.view.move_layer(layer, index)
        self.sync()

    def move_current(self, step: int) -> None:
        """Move the selected layer ``step`` rows (−1 up, +1 down)."""
        layer = self.current_layer()
        if layer is None:
            return
        index = self.view.layers().index(layer) + step
        if 0 <= index < len(self.view.layers()):
            self.view.move_layer(layer, index)
            self.select_layer(layer)

    def zoom_to_current(self) -> None:
        """Show the whole selected layer."""
        layer = self.current_layer()
        if layer is not None:
            self.view.zoom_to_layer(layer)

    def remove_current(self) -> None:
        """Take the selected layer off the map."""
        layer = self.current_layer()
        if layer is not None:
            self.view.remove_layer(layer)

    def _context_menu(self, pos: QtCore.QPoint) -> None:
        item = self.list.itemAt(pos)
        if item is None:
            return
        self.list.setCurrentItem(item)
        self.context_menu().exec_(self.list.viewport().mapToGlobal(pos))

    def context_menu(self) -> QtWidgets.QMenu:
        """The menu of the selected layer: zoom, order, remove."""
        menu = QtWidgets.QMenu(self)
        menu.addAction(tr("Zoom to layer"), self.zoom_to_current)
        up = menu.addAction(tr("Move up"), lambda: self.move_current(-1))
        up.setEnabled(self.up_button.isEnabled())
        down = menu.addAction(tr("Move down"), lambda: self.move_current(1))
        down.setEnabled(self.down_button.isEnabled())
        layer = self.current_layer()
        if getattr(layer, "needs_overviews", False):
            menu.addAction(tr("Build overviews"), self.build_overviews_current)
        menu.addSeparator()
        menu.addAction(tr("Remove layer"), self.remove_current)
        return menu

    def build_overviews_current(self) -> bool:
        """Build the overviews of the selected raster (an ``.ovr`` beside it; the raster
        itself is not changed) so that it draws fast; False with a message when it fails."""
        layer = self.current_layer()
        if layer is None or not hasattr(layer, "build_overviews"):
            return False
        QtWidgets.QApplication.setOverrideCursor(QtCore.Qt.WaitCursor)
        try:
            target = layer.build_overviews()
        except Exception as exc:  # InputError (read-only folder, .ovr exists) or GDAL's
            self.message.emit(tr("Overviews of {0} not built: {1}").format(layer.name, exc))
            return False
        finally:
            QtWidgets.QApplication.restoreOverrideCursor()
        self.message.emit(tr("Overviews written to {0}.").format(target))
        self.view.refresh()
        return True


def _disconnect(signal: object, slot: object) -> None:
    with contextlib.suppress(TypeError, RuntimeError):  # not connected, or the layer is gone
        signal.disconnect(slot)  # type: ignore[attr-defined]


__all__ = ["LayerList", "layer_swatch"]
