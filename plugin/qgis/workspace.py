"""The operator's workspace in QGIS: a PhotoDEM project as a group of styled layers.

Opening a project (:func:`open_workspace`) builds the layer-tree group
"PhotoDEM – <project name>" with three sub-groups:

* **Edits** — every layer of ``edits.gpkg`` (OGR ``path|layername=…``), styled with its QML (editor
  widgets and constraints included) and editable; read-only with a warning when the file cannot
  be written; a missing layer or a missing file is offered to be added/created;
* **Block** — image footprints and stereo models from ``.photodem/block.gpkg``
  (:mod:`...algorithms.project.block_layers`);
* **Products** — what :func:`...algorithms.project.products.find_products` finds; a DSM/DTM is
  two layers of the same file: a hillshade under a 50 % elevation ramp.

Every node carries ``photodem/kind`` and ``photodem/project`` (custom properties, saved in a
``.qgz``), so a project file read again is bound to its group (:meth:`WorkspaceManager.rebind`)
and a product written again replaces its layer (:meth:`Workspace.add_products`). There is one
current workspace (:func:`current_workspace`); opening the same project again replaces its group.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any, Callable, Iterable, List, Optional, Tuple

from qgis.core import (
    Qgis,
    QgsLayerTreeGroup,
    QgsMapLayer,
    QgsProject,
    QgsRasterLayer,
    QgsVectorLayer,
)
from qgis.PyQt.QtCore import QObject, pyqtSignal
from qgis.PyQt.QtWidgets import QPushButton

from ...algorithms.errors import PhotodemError
from ...algorithms.project.block_layers import BLOCK_LAYERS, write_block_layers
from ...algorithms.project.edits import (
    EDIT_LAYERS,
    add_edit_layers,
    create_edits,
    edits_access,
    missing_edit_layers,
)
from ...algorithms.project.model import Project
from ...algorithms.project.products import (
    ELEVATION_KINDS,
    Product,
    classify,
    find_products,
    is_inside,
)
from ..i18n import tr
from .styles import apply_style

KIND = "photodem/kind"
PROJECT = "photodem/project"
#: ``photodem/kind`` of the workspace group and its three sub-groups.
GROUP_KIND, EDITS, BLOCK, PRODUCTS = "workspace", "group:edits", "group:block", "group:products"
MESSAGE_TITLE = "PhotoDEM"
_RASTER_SUFFIXES = (".tif", ".tiff", ".vrt", ".img")
_VECTOR_SUFFIXES = (".gpkg", ".shp", ".geojson", ".json")


def _tag(node_or_layer: Any, kind: str, root: Path) -> None:
    """Set ``photodem/kind`` and ``photodem/project`` on a layer or a layer-tree node."""
    node_or_layer.setCustomProperty(KIND, kind)
    node_or_layer.setCustomProperty(PROJECT, str(root))


def _source_path(layer: QgsMapLayer) -> str:
    """The file of a layer's source, resolved (OGR's ``|layername=…`` removed)."""
    try:
        return str(Path(layer.source().split("|")[0]).resolve())
    except (OSError, ValueError):
        return layer.source()


def workspace_groups(root: Optional[Path] = None) -> List[QgsLayerTreeGroup]:
    """The workspace groups in the current QGIS project (of ``root`` only, when given)."""
    tree = QgsProject.instance().layerTreeRoot()
    wanted = None if root is None else str(Path(root).resolve())
    return [g for g in tree.findGroups() if g.customProperty(KIND) == GROUP_KIND
            and (wanted is None or g.customProperty(PROJECT) == wanted)]


def _remove_group(group: QgsLayerTreeGroup) -> None:
    """Remove a group and its layers from the QGIS project."""
    ids = [node.layerId() for node in group.findLayers()]
    QgsProject.instance().removeMapLayers(ids)
    parent = group.parent()
    if parent is not None:
        parent.removeChildNode(group)


class Workspace(QObject):
    """One open PhotoDEM project in QGIS (see the module notes).

    Parameters
    ----------
    iface : QgisInterface
        For the message bar.
    project : Project
        The loaded project.
    group : QgsLayerTreeGroup, optional
        An existing workspace group to bind to (a ``.qgz`` read again); default: build one.
    """

    #: Emitted when this workspace is opened (built or bound) and when it is closed.
    changed = pyqtSignal()

    def __init__(self, iface: Any, project: Project,
                 group: Optional[QgsLayerTreeGroup] = None) -> None:
        super().__init__()
        self.iface = iface
        self.project = project
        self.root = Path(project.root).resolve()
        self.group = group
        self.read_only = False

    # -- layer tree ----------------------------------------------------------------------------
    @property
    def title(self) -> str:
        """The group name: ``PhotoDEM – <project name>``."""
        return f"PhotoDEM – {self.project.name}"

    def subgroup(self, kind: str) -> Optional[QgsLayerTreeGroup]:
        """The sub-group ``EDITS``, ``BLOCK`` or ``PRODUCTS`` of this workspace."""
        if self.group is None:
            return None
        return next((g for g in self.group.children()
                     if isinstance(g, QgsLayerTreeGroup) and g.customProperty(KIND) == kind), None)

    def build(self) -> None:
        """(Re)build the workspace group: the project's old group is replaced."""
        for old in workspace_groups(self.root):
            _remove_group(old)
        tree = QgsProject.instance().layerTreeRoot()
        self.group = tree.insertGroup(0, self.title)
        _tag(self.group, GROUP_KIND, self.root)
        for kind, name in ((EDITS, tr("Edits")), (BLOCK, tr("Block")),
                           (PRODUCTS, tr("Products"))):
            _tag(self.group.addGroup(name), kind, self.root)
        self.load_edits()
        self.load_block()
        for product in find_products(self.root):
            self._add_product(product, self.subgroup(PRODUCTS), at_top=False)

    def _add_layer(self, layer: QgsMapLayer, kind: str, group: QgsLayerTreeGroup,
                   index: int = -1) -> QgsMapLayer:
        """Style, tag and add ``layer`` to ``group`` at ``index`` (-1: at the end)."""
        apply_style(layer, kind)
        _tag(layer, kind, self.root)
        QgsProject.instance().addMapLayer(layer, False)
        if index < 0:
            group.addLayer(layer)
        else:
            group.insertLayer(index, layer)
        return layer

    # -- edits ---------------------------------------------------------------------------------
    def load_edits(self) -> List[QgsVectorLayer]:
        """Add the layers of ``edits.gpkg`` to the Edits group (emptied first)."""
        group = self.subgroup(EDITS)
        QgsProject.instance().removeMapLayers([n.layerId() for n in group.findLayers()])
        group.removeAllChildren()
        path = self.project.edits_path
        if not path.is_file():
            self._offer(tr("The project has no edits.gpkg: start points, exclusion areas and "
                           "breaklines cannot be drawn."), tr("Create edits.gpkg"),
                        self.create_edits)
            return []
        problem = edits_access(path)
        self.read_only = problem is not None and problem[0] == "read-only"
        if self.read_only:
            self._message(tr("{0} cannot be written: the edit layers are loaded read-only.")
                          .format(path), Qgis.Warning)
        try:
            missing = missing_edit_layers(path)
        except PhotodemError as exc:
            self._message(str(exc), Qgis.Critical)
            return []
        layers = [self._edit_layer(path, name, group) for name in EDIT_LAYERS
                  if name not in missing]
        if missing and not self.read_only:
            self._offer(tr("edits.gpkg lacks the layer(s) {0}.").format(", ".join(missing)),
                        tr("Add them"), lambda: self.add_missing_layers(missing))
        return [layer for layer in layers if layer is not None]

    def _edit_layer(self, path: Path, name: str, group: QgsLayerTreeGroup,
                    index: int = -1) -> Optional[QgsVectorLayer]:
        """One layer of ``edits.gpkg`` added to the Edits group (read-only when the file is)."""
        layer = QgsVectorLayer(f"{path}|layername={name}", edit_layer_title(name), "ogr")
        if not layer.isValid():
            self._message(tr("Cannot load the layer {0} of {1}.").format(name, path),
                          Qgis.Warning)
            return None
        if self.read_only:
            layer.setReadOnly(True)
        return self._add_layer(layer, f"edit:{name}", group, index)

    def create_edits(self) -> None:
        """Create the missing ``edits.gpkg`` (all edit layers) and load it."""
        try:
            create_edits(self.project.edits_path, self.project.crs)
        except PhotodemError as exc:
            self._message(str(exc), Qgis.Critical)
            return
        self.load_edits()

    def add_missing_layers(self, names: Iterable[str]) -> None:
        """Add the edit layers ``names`` to ``edits.gpkg`` and to the Edits group in their
        place; the other layers are not touched. Refused while a layer of the file is being
        edited: a second writer of the GeoPackage would break QGIS's open connections."""
        names = list(names)
        path = self.project.edits_path
        busy = [layer.name() for layer in self.layers_in(EDITS) if layer.isEditable()]
        if busy:
            self._message(tr("Save or discard the edits of {0} first; edits.gpkg was not "
                             "changed.").format(", ".join(busy)), Qgis.Warning)
            self._offer(tr("edits.gpkg lacks the layer(s) {0}.").format(", ".join(names)),
                        tr("Add them"), lambda: self.add_missing_layers(names))
            return
        try:
            added = add_edit_layers(path, self.project.crs, names)
        except PhotodemError as exc:
            self._message(str(exc), Qgis.Critical)
            return
        for layer in self.layers_in(EDITS):  # their connections do not see the new table
            layer.dataProvider().reloadData()
            layer.reload()
        group = self.subgroup(EDITS)
        for name in added:
            self._edit_layer(path, name, group, _edit_index(group, name))

    def edit_layer(self, name: str) -> Optional[QgsVectorLayer]:
        """The layer ``name`` of ``edits.gpkg`` in the Edits group, or ``None``."""
        return next(iter(self.layers(f"edit:{name}", EDITS)), None)

    # -- block ---------------------------------------------------------------------------------
    def load_block(self) -> List[QgsVectorLayer]:
        """Add footprints and stereo models (``.photodem/block.gpkg``, rewritten first when
        ``project.toml`` is newer) to the Block group, replacing the layers it holds (they
        are removed first: Windows cannot replace a file that is open)."""
        group = self.subgroup(BLOCK)
        QgsProject.instance().removeMapLayers([n.layerId() for n in group.findLayers()])
        group.removeAllChildren()
        try:
            path = write_block_layers(self.project)
        except (PhotodemError, OSError) as exc:
            self._message(tr("The block layers cannot be made: {0}").format(exc), Qgis.Warning)
            return []
        names = {"footprints": tr("Image footprints"), "stereo_models": tr("Stereo models")}
        out = []
        for layer_name in reversed(list(BLOCK_LAYERS)):  # stereo models above the footprints
            layer = QgsVectorLayer(f"{path}|layername={layer_name}", names[layer_name], "ogr")
            if layer.isValid():
                out.append(self._add_layer(layer, layer_name, group))
        return out

    # -- products ------------------------------------------------------------------------------
    def _add_product(self, product: Product, group: QgsLayerTreeGroup,
                     at_top: bool) -> List[QgsMapLayer]:
        """The layers of one product (a DEM: ramp above hillshade) added to ``group``, on top
        or at the end; returns them top to bottom."""
        path, label = str(product.path), _product_label(product)
        if product.kind in ("seamlines", "vector"):
            layer = QgsVectorLayer(layer_uri(product), label, "ogr")
        else:
            layer = QgsRasterLayer(path, label, "gdal")
        if not layer.isValid():
            self._message(tr("Cannot load {0}.").format(path), Qgis.Warning)
            return []
        layers = [(layer, product.kind)]
        if product.kind in ELEVATION_KINDS:
            shade = QgsRasterLayer(path, f"{label} ({tr('hillshade')})", "gdal")
            layers.append((shade, "hillshade"))
        for item, kind in (reversed(layers) if at_top else layers):
            self._add_layer(item, kind, group, 0 if at_top else -1)
        return [item for item, _ in layers]

    def add_products(self, paths: Iterable[str]) -> List[QgsMapLayer]:
        """Add product files to the map, styled, replacing older layers of the same files.

        Files below the project go into the Products group (on top: newest first), others to
        the top of the layer tree. Files that are no known product are added with QGIS's
        default style when QGIS can read them.
        """
        added: List[QgsMapLayer] = []
        for raw in paths:
            path = Path(str(raw)).resolve()
            if not path.is_file():
                continue
            self.remove_layers_of(path)
            inside = is_inside(path, self.root)
            group = (self.subgroup(PRODUCTS) if inside and self.group is not None
                     else QgsProject.instance().layerTreeRoot())
            product = classify(path) or _generic_product(path)
            if product is None:
                continue
            layers = self._add_product(product, group, at_top=True)
            if not inside:  # not a product of this project
                for layer in layers:
                    layer.setCustomProperty(PROJECT, "")
            added += layers
        if added:
            self.iface.mapCanvas().refresh()
        return added

    def adopt(self, layer: QgsMapLayer, kind: str) -> None:
        """Take a layer that Processing loaded for a run into the Products group (on top),
        replacing older layers of the same file; a DEM gets its hillshade below it."""
        path = Path(_source_path(layer))
        self.remove_layers_of(path, keep=layer)
        _tag(layer, kind, self.root)
        group = self.subgroup(PRODUCTS)
        tree = QgsProject.instance().layerTreeRoot()
        node = tree.findLayer(layer.id())
        if group is None or node is None:
            return
        if node.parent() is not group:
            group.insertChildNode(0, node.clone())
            node.parent().removeChildNode(node)
        if kind in ELEVATION_KINDS:
            shade = QgsRasterLayer(str(path), f"{layer.name()} ({tr('hillshade')})", "gdal")
            if shade.isValid():
                apply_style(shade, "hillshade")
                _tag(shade, "hillshade", self.root)
                QgsProject.instance().addMapLayer(shade, False)
                index = group.children().index(group.findLayer(layer.id()))
                group.insertLayer(index + 1, shade)

    def remove_layers_of(self, path: Path, keep: Optional[QgsMapLayer] = None) -> int:
        """Remove every PhotoDEM layer whose source is ``path`` (but ``keep``); returns how
        many."""
        wanted = str(Path(path).resolve())
        ids = [layer.id() for layer in QgsProject.instance().mapLayers().values()
               if _source_path(layer) == wanted and layer.customProperty(KIND)
               and layer is not keep and (keep is None or layer.id() != keep.id())]
        QgsProject.instance().removeMapLayers(ids)
        return len(ids)

    def layers_in(self, subgroup: str) -> List[QgsMapLayer]:
        """Every layer of a sub-group, in layer-tree order."""
        group = self.subgroup(subgroup)
        if group is None:
            return []
        return [n.layer() for n in group.findLayers() if n.layer() is not None]

    def layers(self, kind: str, subgroup: str = PRODUCTS) -> List[QgsMapLayer]:
        """The layers of one kind in a sub-group, in layer-tree order."""
        group = self.subgroup(subgroup)
        if group is None:
            return []
        return [n.layer() for n in group.findLayers()
                if n.layer() is not None and n.layer().customProperty(KIND) == kind]

    def surface_layers(self) -> List[QgsRasterLayer]:
        """The DSM and DTM layers of the Products group: DSMs first, newest first."""
        found: List[Tuple[int, float, QgsRasterLayer]] = []
        for rank, kind in enumerate(ELEVATION_KINDS):
            for layer in self.layers(kind):
                try:
                    mtime = Path(_source_path(layer)).stat().st_mtime
                except OSError:
                    mtime = 0.0
                found.append((rank, -mtime, layer))
        return [layer for _, _, layer in sorted(found, key=lambda t: t[:2])]

    # -- life cycle ----------------------------------------------------------------------------
    def close(self, remove_group: bool = True) -> None:
        """Close the workspace: its group (and layers) leave the map unless ``remove_group``
        is False; the current workspace becomes ``None``."""
        if remove_group and self.group is not None:
            with contextlib.suppress(RuntimeError):  # deleted with the QGIS project
                _remove_group(self.group)
        self.group = None
        _set_current(None, self)
        self.changed.emit()

    # -- messages ------------------------------------------------------------------------------
    def _message(self, text: str, level: Any = Qgis.Info) -> None:
        if self.iface is not None:
            self.iface.messageBar().pushMessage(MESSAGE_TITLE, text, level, 8)

    def _offer(self, text: str, button: str, action: Callable[[], None]) -> None:
        """A message-bar warning with one button that runs ``action``."""
        if self.iface is None:
            return
        bar = self.iface.messageBar()
        item = bar.createMessage(MESSAGE_TITLE, text)
        push = QPushButton(button, item)
        push.setObjectName("photodemOffer")

        def run() -> None:
            bar.popWidget(item)
            action()

        push.clicked.connect(run)
        item.layout().addWidget(push)
        bar.pushWidget(item, Qgis.Warning)


def edit_layer_title(name: str) -> str:
    """The name an edit layer of ``edits.gpkg`` shows in the layer tree (translated); the layer
    is found by its kind ``edit:<name>``, never by this title."""
    titles = {"start_points": tr("Start points"), "exclusion_areas": tr("Exclusion areas"),
              "boundaries": tr("Boundaries"), "breaklines": tr("Breaklines"),
              "ground_points": tr("Ground points"), "seamlines": tr("Seamlines"),
              "check_points": tr("Check points")}
    return titles.get(name, name)


def _edit_index(group: QgsLayerTreeGroup, name: str) -> int:
    """Where the edit layer ``name`` goes in the Edits group: after the layers that come
    before it in :data:`EDIT_LAYERS`."""
    order = list(EDIT_LAYERS)
    before = {f"edit:{other}" for other in order[:order.index(name)]}
    return sum(1 for node in group.findLayers()
               if node.layer() is not None and node.layer().customProperty(KIND) in before)


def _product_label(product: Product) -> str:
    """The layer name of a product: ``DSM 0101_0102``, ``Ortho 0203``…"""
    names = {"dsm": tr("DSM"), "dtm": tr("DTM"), "difference": tr("Difference"),
             "ortho": tr("Ortho"), "mosaic": tr("Mosaic"), "seamlines": tr("Seamlines")}
    return f"{names.get(product.kind, product.kind)} {product.name}"


def layer_uri(product: Product) -> str:
    """The QGIS source of a product: the file, or its ``seamlines`` layer for the seamline
    GeoPackage of a mosaic (which holds the footprints too)."""
    if product.kind == "seamlines":
        return f"{product.path}|layername=seamlines"
    return str(product.path)


def _generic_product(path: Path) -> Optional[Product]:
    """A file that is no known product, as a plain raster or vector layer (or ``None``)."""
    suffix = path.suffix.lower()
    if suffix in _RASTER_SUFFIXES:
        return Product("raster", path.stem, path)
    if suffix in _VECTOR_SUFFIXES:
        return Product("vector", path.stem, path)
    return None


def product_label(product: Optional[Product], fallback: str = "") -> str:
    """The layer name of a product (``fallback`` for ``None``)."""
    return _product_label(product) if product is not None else fallback


def place_output_layer(layer: QgsMapLayer, kind: Optional[str] = None) -> None:
    """Style a layer that Processing loaded at the end of a run (``kind`` or what the file
    is); a file under the open workspace's project goes into its Products group."""
    path = Path(_source_path(layer))
    if kind is None:
        product = classify(path)
        kind = product.kind if product is not None else None
    if kind:
        apply_style(layer, kind)
        layer.setCustomProperty(KIND, kind)
    workspace = current_workspace()
    if workspace is not None and workspace.group is not None and is_inside(path, workspace.root):
        workspace.adopt(layer, kind or "layer")


# -- the current workspace -----------------------------------------------------------------------
class WorkspaceNotifier(QObject):
    """Tells listeners (toolbars, actions) which workspace is current: ``changed(workspace)``
    with ``None`` when no project is open."""

    changed = pyqtSignal(object)


_current: Optional[Workspace] = None
_notifier = WorkspaceNotifier()


def workspace_notifier() -> WorkspaceNotifier:
    """The one :class:`WorkspaceNotifier`."""
    return _notifier


def current_workspace() -> Optional[Workspace]:
    """The open workspace, or ``None`` when no project is open."""
    return _current


def _set_current(workspace: Optional[Workspace], closing: Optional[Workspace] = None) -> None:
    global _current
    if closing is not None and _current is not closing:
        return
    _current = workspace
    _notifier.changed.emit(workspace)


def open_workspace(iface: Any, path: Any) -> Workspace:
    """Open the project at ``path`` (its folder or ``project.toml``) as the current workspace.

    Raises
    ------
    InputError
        When ``path`` is no readable PhotoDEM project; nothing is added to the map then.
    """
    project = Project.load(path)
    if _current is not None and _current.root == Path(project.root).resolve():
        _current.close()
    workspace = Workspace(iface, project)
    workspace.build()
    _set_current(workspace)
    workspace.changed.emit()
    return workspace


def bind_workspace(iface: Any) -> Optional[Workspace]:
    """Bind the current workspace to a workspace group of the QGIS project just read (the
    first one whose project still loads), or ``None``."""
    for group in workspace_groups():
        try:
            project = Project.load(group.customProperty(PROJECT))
        except PhotodemError as exc:
            if iface is not None:
                iface.messageBar().pushMessage(MESSAGE_TITLE, str(exc), Qgis.Warning, 8)
            continue
        workspace = Workspace(iface, project, group)
        _set_current(workspace)
        workspace.changed.emit()
        return workspace
    if _current is not None:
        _current.group = None
        _current.close(remove_group=False)
    return None


def forget_workspace() -> None:
    """The QGIS project was cleared: its groups are gone, no workspace is current."""
    if _current is not None:
        _current.group = None
        _current.close(remove_group=False)


__all__ = ["BLOCK", "EDITS", "GROUP_KIND", "KIND", "PRODUCTS", "PROJECT", "Workspace",
           "WorkspaceNotifier", "bind_workspace", "current_workspace", "forget_workspace",
           "layer_uri", "open_workspace", "place_output_layer", "product_label", "workspace_groups",
           "workspace_notifier"]
