"""The operator's edits of one project in memory, with undo/redo and an atomic save.

The standalone tool edits ``edits.gpkg`` the way QGIS does with its edit buffer: the features
are read once into memory (:func:`~photodem.algorithms.project.edits_save.read_edits`), every
change is a :class:`QtWidgets.QUndoCommand` on :attr:`EditSession.undo_stack`, and *Save*
writes the whole file at once (:func:`~photodem.algorithms.project.edits_save.save_edits`:
staging copy, check, rename), so QGIS can read the file at every moment and a failed save
changes nothing.

A file that cannot be read (damaged, not a GeoPackage) or not written (read-only, locked by
another program) opens the session read-only: :attr:`EditSession.problem` says what and where,
every change raises :class:`~photodem.algorithms.errors.InputError`, and nothing is written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

from ...algorithms.errors import InputError
from ...algorithms.project.edits import EDIT_LAYERS, check_layer, edits_access
from ...algorithms.project.edits_save import read_edits, save_edits
from ..i18n import tr
from ..qt import QtCore, QtWidgets, pyqtSignal

PathLike = Union[str, Path]
#: A feature of the session: (fid, shapely geometry, attributes).
Feature = Tuple[int, Any, Dict[str, Any]]
#: What a command puts in place of a feature: (geometry, attributes), or None (no feature).
State = Optional[Tuple[Any, Dict[str, Any]]]

EDITS_FILE = "edits.gpkg"


def add_text(layer: str) -> str:
    """The undo text of a new feature of ``layer`` ("Add start point")."""
    texts = {"start_points": tr("Add start point"), "exclusion_areas": tr("Add exclusion area"),
             "boundaries": tr("Add boundary"), "breaklines": tr("Add breakline"),
             "ground_points": tr("Add ground point"), "seamlines": tr("Add seamline"),
             "check_points": tr("Add check point")}
    return texts.get(layer, tr("Add feature"))


def change_text(layer: str) -> str:
    """The undo text of a changed feature of ``layer`` ("Change breakline")."""
    texts = {"start_points": tr("Change start point"),
             "exclusion_areas": tr("Change exclusion area"),
             "boundaries": tr("Change boundary"), "breaklines": tr("Change breakline"),
             "ground_points": tr("Change ground point"), "seamlines": tr("Change seamline"),
             "check_points": tr("Change check point")}
    return texts.get(layer, tr("Change feature"))


def delete_text(layer: str) -> str:
    """The undo text of a removed feature of ``layer`` ("Delete exclusion area")."""
    texts = {"start_points": tr("Delete start point"),
             "exclusion_areas": tr("Delete exclusion area"),
             "boundaries": tr("Delete boundary"), "breaklines": tr("Delete breakline"),
             "ground_points": tr("Delete ground point"), "seamlines": tr("Delete seamline"),
             "check_points": tr("Delete check point")}
    return texts.get(layer, tr("Delete feature"))


class _Change(QtWidgets.QUndoCommand):
    """Put ``after`` in place of ``before`` for one feature (either may be None: add, remove)."""

    def __init__(self, session: EditSession, layer: str, fid: int, before: State,
                 after: State, text: str) -> None:
        super().__init__(text)
        self.session, self.layer, self.fid = session, layer, fid
        self.before, self.after = before, after

    def redo(self) -> None:
        self.session._put(self.layer, self.fid, self.after)

    def undo(self) -> None:
        self.session._put(self.layer, self.fid, self.before)


def ask_save(parent: Optional[QtWidgets.QWidget], session: EditSession) -> str:
    """The close question for unsaved edits: ``"save"``, ``"discard"`` or ``"cancel"``."""
    box = QtWidgets.QMessageBox(parent)
    box.setIcon(QtWidgets.QMessageBox.Question)
    box.setWindowTitle(tr("Unsaved edits"))
    box.setText(tr("The edits of this project are not saved. Save them to {0}?").format(
        session.path))
    save = box.addButton(QtWidgets.QMessageBox.Save)
    discard = box.addButton(QtWidgets.QMessageBox.Discard)
    box.addButton(QtWidgets.QMessageBox.Cancel)
    save.setText(tr("Save"))
    discard.setText(tr("Discard"))
    box.button(QtWidgets.QMessageBox.Cancel).setText(tr("Cancel"))
    box.setDefaultButton(save)
    box.exec_()
    clicked = box.clickedButton()
    return "save" if clicked is save else "discard" if clicked is discard else "cancel"


class EditSession(QtCore.QObject):
    """The edits of one project in memory (see the module notes).

    Parameters
    ----------
    project_root : path
        The project folder (``edits.gpkg`` lies in it).
    parent : QObject, optional
    crs : str, optional
        The project CRS for a file that must be created on save; default: read from
        ``project.toml`` when needed.

    Attributes
    ----------
    path : Path
        ``<project_root>/edits.gpkg``.
    read_only : bool
        The file cannot be read or written; :attr:`problem` says why.
    problem : str
        Empty, or what is wrong with the file and where.
    undo_stack : QUndoStack
        Every change; clean = as in the file.
    ask : callable
        ``ask(parent, session) -> "save" | "discard" | "cancel"`` (tests replace it).

    Signals
    -------
    changed(str)
        A feature of the layer was added, changed or removed (also by undo/redo).
    dirty_changed(bool)
        The session has (True) or no longer has (False) unsaved edits.
    saved(str)
        The file was written (its path).
    """

    changed = pyqtSignal(str)
    dirty_changed = pyqtSignal(bool)
    saved = pyqtSignal(str)

    def __init__(self, project_root: PathLike, parent: Optional[QtCore.QObject] = None,
                 crs: str = "") -> None:
        super().__init__(parent)
        self.root = Path(project_root)
        self.path = self.root / EDITS_FILE
        self.read_only = False
        self.problem = ""
        self.ask: Callable[[Any, EditSession], str] = ask_save
        self._crs = crs
        self._layers: Dict[str, Dict[int, Tuple[Any, Dict[str, Any]]]] = {
            name: {} for name in EDIT_LAYERS}
        self._columns: Dict[str, List[str]] = {n: list(f) for n, (_, f) in EDIT_LAYERS.items()}
        self._next_fid: Dict[str, int] = dict.fromkeys(EDIT_LAYERS, 1)
        self.undo_stack = QtWidgets.QUndoStack(self)
        self.undo_stack.cleanChanged.connect(self._clean_changed)
        self._load()

    def _clean_changed(self, clean: bool) -> None:
        self.dirty_changed.emit(not clean)

    # -- loading ---------------------------------------------------------------------------
    def _load(self) -> None:
        """Read every edit layer; a bad file makes the session read-only with the reason."""
        if not self.path.exists():
            return  # created on save
        try:
            content = read_edits(self.path)
        except InputError as exc:
            self._refuse(tr("The edits file {0} cannot be read: {1} It is shown read-only and "
                            "never written.").format(self.path, exc))
            return
        self._crs = self._crs or content.crs_wkt
        for name, features in content.layers.items():
            self._layers[name] = {fid: (geometry, attrs) for fid, geometry, attrs in features}
            self._columns[name] = list(content.columns[name])
            self._next_fid[name] = max(self._layers[name], default=0) + 1
        access = edits_access(self.path)
        if access is not None:
            kind, detail = access
            if kind == "read-only":
                self._refuse(tr("The edits file {0} is read-only ({1}); make it writable to "
                                "edit.").format(self.path, detail))
            else:
                self._refuse(tr("The edits file {0} is locked or unreadable ({1}); close the "
                                "program that holds it and open the project again.").format(
                                    self.path, detail))

    def _refuse(self, problem: str) -> None:
        self.read_only = True
        self.problem = problem

    # -- reading ---------------------------------------------------------------------------
    @property
    def dirty(self) -> bool:
        """Unsaved edits exist."""
        return not self.undo_stack.isClean()

    @property
    def crs(self) -> str:
        """The CRS of the edits (the file's, else the project's; may be empty)."""
        if not self._crs:
            self._crs = self._project_crs()
        return self._crs

    def _project_crs(self) -> str:
        from ...algorithms.project.model import Project  # lazy: only to create a missing file

        try:
            return str(Project.load(self.root).crs or "")
        except InputError:
            return ""

    def layers(self) -> List[str]:
        """The edit layers (the order of :data:`EDIT_LAYERS`)."""
        return list(EDIT_LAYERS)

    def features(self, layer: str) -> List[Feature]:
        """The features of ``layer`` with a geometry, in fid order."""
        items = self._layers[check_layer(layer)].items()
        return [(fid, g, dict(a)) for fid, (g, a) in sorted(items) if g is not None]

    def feature(self, layer: str, fid: int) -> Optional[Tuple[Any, Dict[str, Any]]]:
        """``(geometry, attributes)`` of one feature, or None."""
        item = self._layers[check_layer(layer)].get(int(fid))
        return None if item is None else (item[0], dict(item[1]))

    def source(self, layer: str) -> Callable[[], List[Feature]]:
        """The callable :meth:`MapView.add_vector` draws ``layer`` from."""
        check_layer(layer)
        return lambda: self.features(layer)

    # -- changing --------------------------------------------------------------------------
    def _writable(self, layer: str) -> str:
        if self.read_only:
            raise InputError(self.problem)
        return check_layer(layer)

    def _attributes(self, layer: str, attributes: Optional[Dict[str, Any]]) -> Dict[str, Any]:
        """Every column of the layer, ``None`` where not given; unknown fields refused."""
        attributes = dict(attributes or {})
        unknown = sorted(set(attributes) - set(self._columns[layer]))
        if unknown:
            raise InputError(tr("Layer '{0}' has no field(s) {1}.").format(
                layer, ", ".join(unknown)))
        return {c: attributes.get(c) for c in self._columns[layer]}

    def add(self, layer: str, geometry: Any, attributes: Optional[Dict[str, Any]] = None,
            text: str = "") -> int:
        """Add a feature (one undo command); returns its fid."""
        self._writable(layer)
        fid = self._next_fid[layer]
        self._next_fid[layer] = fid + 1
        after = (geometry, self._attributes(layer, attributes))
        self.undo_stack.push(_Change(self, layer, fid, None, after, text or add_text(layer)))
        return fid

    def replace(self, layer: str, fid: int, geometry: Any,
                attributes: Optional[Dict[str, Any]] = None, text: str = "") -> None:
        """Change a feature's geometry (and attributes, when given) as one undo command."""
        self._writable(layer)
        before = self._existing(layer, fid)
        attrs = before[1] if attributes is None else self._attributes(layer, attributes)
        self.undo_stack.push(_Change(self, layer, int(fid), before, (geometry, dict(attrs)),
                                     text or change_text(layer)))

    def remove(self, layer: str, fid: int, text: str = "") -> None:
        """Remove a feature (one undo command)."""
        self._writable(layer)
        before = self._existing(layer, fid)
        self.undo_stack.push(_Change(self, layer, int(fid), before, None,
                                     text or delete_text(layer)))

    def _existing(self, layer: str, fid: int) -> Tuple[Any, Dict[str, Any]]:
        item = self._layers[layer].get(int(fid))
        if item is None:
            raise InputError(tr("Layer '{0}' has no feature {1}.").format(layer, fid))
        return item[0], dict(item[1])

    def _put(self, layer: str, fid: int, state: State) -> None:
        """Set (or drop) one feature; the commands' only way to change the memory."""
        if state is None:
            self._layers[layer].pop(fid, None)
        else:
            self._layers[layer][fid] = (state[0], dict(state[1]))
        self.changed.emit(layer)

    # -- saving ----------------------------------------------------------------------------
    def save(self) -> Path:
        """Write every edit layer to ``edits.gpkg`` atomically and mark the stack clean.

        Raises
        ------
        InputError
            A read-only session, or a write that failed (the file is then unchanged).
        """
        if self.read_only:
            raise InputError(self.problem)
        layers = {name: [(fid, g, a) for fid, (g, a) in sorted(items.items())]
                  for name, items in self._layers.items()}
        path = save_edits(self.path, layers, self.crs)
        self.undo_stack.setClean()
        self.saved.emit(str(path))
        return path

    def maybe_save(self, parent: Optional[QtWidgets.QWidget] = None) -> bool:
        """Ask about unsaved edits before closing; True when closing may go on.

        Save (and it worked) or Discard → True; Cancel, or a save that failed (its message
        shown) → False. Without unsaved edits → True without asking.
        """
        if not self.dirty or self.read_only:
            return True
        answer = self.ask(parent, self)
        if answer == "discard":
            return True
        if answer != "save":
            return False
        try:
            self.save()
        except InputError as exc:
            QtWidgets.QMessageBox.critical(parent, tr("Edits not saved"), str(exc))
            return False
        return True


def edit_layer_title(name: str) -> str:
    """The name of an edit layer in the layer list (translated; the same as in QGIS)."""
    titles = {"start_points": tr("Start points"), "exclusion_areas": tr("Exclusion areas"),
              "boundaries": tr("Boundaries"), "breaklines": tr("Breaklines"),
              "ground_points": tr("Ground points"), "seamlines": tr("Seamlines"),
              "check_points": tr("Check points")}
    return titles.get(name, name)


def show_edits(view: Any, session: EditSession) -> List[Any]:
    """Add one vector layer per edit layer to a MapView (kind ``edit:<layer>``, drawn from the
    session's memory, the first edit layer on top) and draw each again when the session
    changes it. Layers of that kind already in the view are replaced. Returns the layers."""
    added = []
    for name in reversed(list(EDIT_LAYERS)):
        old = view.layer_by_kind(f"edit:{name}")
        if old is not None:
            view.remove_layer(old)
        added.append(view.add_vector(session.source(name), f"edit:{name}",
                                     name=edit_layer_title(name)))

    def redraw(layer: str) -> None:
        try:
            drawn = view.layer_by_kind(f"edit:{layer}")
        except RuntimeError:  # the view was closed before the session
            return
        if drawn is not None and hasattr(drawn, "reload"):
            drawn.reload()

    session.changed.connect(redraw)
    return added[::-1]


__all__ = ["EDITS_FILE", "EditSession", "add_text", "ask_save", "change_text", "delete_text",
           "edit_layer_title", "show_edits"]
