"""A parameter form generated from an algorithm spec (standalone toolbox; reusable in QGIS docks).

One editor per :class:`~photodem.algorithms.processing.spec.Parameter`, chosen by its kind:

=====================================  ==============================================
kind                                   editor
=====================================  ==============================================
raster, vector, file, project, folder  line edit + "…" button (open file / folder)
output_*                               line edit + "…" button (save file / folder)
multiple_rasters                       line edit (comma-separated) + "…" (several)
number, integer                        spin box with unit suffix and range
                                       (line edit when optional without default)
enum                                   combo box of the options
bool                                   check box
model, image                           editable combo, filled from the chosen project
crs, string, extent                    line edit with a placeholder
=====================================  ==============================================

:meth:`ParameterForm.values` returns the *raw* parameter dict (what
:func:`~photodem.algorithms.processing.registry.run` takes): empty fields are left out, so the
spec's defaults and "required" checks apply exactly as in the CLI and QGIS.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

from ...algorithms.processing.spec import Algorithm, Parameter
from ...algorithms.project.model import Project
from ..i18n import tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal

#: Settings keys (``QSettings`` standalone, ``QgsSettings`` in QGIS): the last raw values of
#: each algorithm (JSON) and the last project.
SETTINGS_PARAMS = "PhotoDEM/params/"
SETTINGS_PROJECT = "PhotoDEM/last_project"
_INT_LIMIT = 2**31 - 1
_FLOAT_LIMIT = 1e12


class PathEdit(QtWidgets.QWidget):
    """A line edit with a "…" button that opens a file or folder dialog.

    Parameters
    ----------
    mode : str
        ``"open"``, ``"open_many"``, ``"save"`` or ``"folder"``.
    extensions : sequence of str
        File name endings for the dialog filter (``".tif"``).
    """

    text_changed = pyqtSignal(str)

    def __init__(self, mode: str = "open", extensions: tuple = (),
                 parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self.mode = mode
        self.extensions = tuple(extensions)
        self.line_edit = QtWidgets.QLineEdit(self)
        self.line_edit.setClearButtonEnabled(True)
        self.button = QtWidgets.QToolButton(self)
        self.button.setText("…")
        self.button.setToolTip(tr("Browse"))
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setSpacing(4)
        layout.addWidget(self.line_edit, 1)
        layout.addWidget(self.button)
        self.button.clicked.connect(self.browse)
        self.line_edit.textChanged.connect(self.text_changed)

    def text(self) -> str:
        return self.line_edit.text()

    def setText(self, text: str) -> None:  # noqa: N802 - Qt naming
        self.line_edit.setText(text)

    def _filter(self) -> str:
        if not self.extensions:
            return tr("All files (*)")
        patterns = " ".join(f"*{e}" for e in self.extensions)
        return f"{tr('Supported files')} ({patterns});;{tr('All files (*)')}"

    def browse(self) -> None:
        start = self.text().split(",")[0].strip() or str(Path.home())
        dialog = QtWidgets.QFileDialog
        if self.mode == "folder":
            path = dialog.getExistingDirectory(self, tr("Choose a folder"), start)
        elif self.mode == "save":
            path = dialog.getSaveFileName(self, tr("Save as"), start, self._filter())[0]
        elif self.mode == "open_many":
            paths = dialog.getOpenFileNames(self, tr("Choose files"), start, self._filter())[0]
            path = ",".join(paths)
        else:
            path = dialog.getOpenFileName(self, tr("Choose a file"), start, self._filter())[0]
        if path:
            self.setText(path)


class _Editor:
    """An editor widget with a getter (raw value or ``None``) and a setter."""

    def __init__(self, widget: QtWidgets.QWidget, get: Callable[[], Any],
                 put: Callable[[Any], None], changed: Any) -> None:
        self.widget = widget
        self.get = get
        self.put = put
        self.changed = changed


def _text_value(text: str) -> Optional[str]:
    text = text.strip()
    return text or None


def _make_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """The editor of ``p``, chosen by what its kind means (see the table above)."""
    if p.is_path:
        return _path_editor(p, parent)
    if p.is_numeric and (p.default is not None or not p.optional):
        return _number_editor(p, parent)
    if p.is_numeric:  # optional without default: may stay empty
        return _optional_number_editor(p, parent)
    if p.is_choice:
        return _choice_editor(p, parent)
    if p.is_bool:
        w = QtWidgets.QCheckBox(parent)
        w.setChecked(bool(p.default))
        return _Editor(w, w.isChecked, lambda v: w.setChecked(bool(v)), w.toggled)
    if p.is_item_name:
        return _item_editor(p, parent)
    return _text_editor(p, parent)


def _path_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """A path with a browse button: a folder, a file to save, several files or one file."""
    if p.is_folder:
        mode = "folder"
    elif p.is_output:
        mode = "save"
    elif p.is_list:
        mode = "open_many"
    else:
        mode = "open"
    w = PathEdit(mode, p.extensions, parent)
    if p.default is not None:
        w.setText(str(p.default))
    if p.is_project:
        w.line_edit.setPlaceholderText(tr("project folder (with project.toml)"))
    elif p.is_list:
        w.line_edit.setPlaceholderText(tr("several files, separated by commas"))
    return _Editor(w, lambda: _text_value(w.text()), lambda v: w.setText(_as_text(v)),
                   w.text_changed)


def _number_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """A spin box within the parameter's range, with its unit."""
    if p.is_integer:
        w = QtWidgets.QSpinBox(parent)
        low = -_INT_LIMIT if p.minimum is None else int(max(p.minimum, -_INT_LIMIT))
        high = _INT_LIMIT if p.maximum is None else int(min(p.maximum, _INT_LIMIT))
    else:
        w = QtWidgets.QDoubleSpinBox(parent)
        low = -_FLOAT_LIMIT if p.minimum is None else p.minimum
        high = _FLOAT_LIMIT if p.maximum is None else p.maximum
        w.setDecimals(_decimals(p))
        span = high - low
        w.setSingleStep(0.1 if span <= 10 else 1.0)
    w.setRange(low, high)
    w.setAccelerated(True)
    w.setKeyboardTracking(False)
    if p.unit:
        w.setSuffix(f" {p.unit}")
    w.setValue(p.default if p.default is not None else max(low, min(0, high)))
    w.setMinimumWidth(120)
    integer = p.is_integer
    return _Editor(w, w.value, lambda v: w.setValue(int(v) if integer else float(v)),
                   w.valueChanged)


def _optional_number_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """A line edit that accepts numbers only and may stay empty."""
    w = QtWidgets.QLineEdit(parent)
    w.setPlaceholderText(tr("optional") + (f" [{p.unit}]" if p.unit else ""))
    validator: QtGui.QValidator
    if p.is_integer:
        validator = QtGui.QIntValidator(w)
    else:
        validator = QtGui.QDoubleValidator(w)
        validator.setLocale(QtCore.QLocale.c())
    w.setValidator(validator)
    return _Editor(w, lambda: _text_value(w.text()), lambda v: w.setText(_as_text(v)),
                   w.textChanged)


def _choice_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """A combo box of the options (translated labels, the option strings as data)."""
    w = QtWidgets.QComboBox(parent)
    if p.optional and p.default is None:
        w.addItem("", None)
    for option in p.options:
        w.addItem(tr(option), option)
    if p.default is not None:
        w.setCurrentIndex(max(w.findData(p.default), 0))
    return _Editor(w, lambda: w.currentData(),
                   lambda v: w.setCurrentIndex(max(w.findData(v), 0)),
                   w.currentIndexChanged)


def _item_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """An editable combo box of the project's models or images (filled by the form)."""
    w = QtWidgets.QComboBox(parent)
    w.setEditable(True)
    w.setInsertPolicy(QtWidgets.QComboBox.NoInsert)
    w.lineEdit().setPlaceholderText(
        tr("choose a project first") if p.kind == "model" else tr("image name"))
    if p.default is not None:
        w.setEditText(str(p.default))
    return _Editor(w, lambda: _text_value(w.currentText()),
                   lambda v: w.setEditText(_as_text(v)), w.currentTextChanged)


def _text_editor(p: Parameter, parent: QtWidgets.QWidget) -> _Editor:
    """A line edit: a CRS, an extent or free text."""
    w = QtWidgets.QLineEdit(parent)
    w.setPlaceholderText({
        "crs": tr("e.g. EPSG:25832"),
        "extent": tr("xmin,ymin,xmax,ymax"),
    }.get(p.kind, tr("optional") if p.optional else ""))
    if p.default is not None:
        w.setText(_as_text(p.default))
    return _Editor(w, lambda: _text_value(w.text()), lambda v: w.setText(_as_text(v)),
                   w.textChanged)


def _as_text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, (list, tuple)):
        return ",".join(str(v) for v in value)
    return str(value)


def _decimals(p: Parameter) -> int:
    """Enough decimals for the default and the bounds (at least 2, at most 6)."""
    decimals = 2
    for v in (p.default, p.minimum, p.maximum):
        if isinstance(v, float) and v != int(v):
            text = f"{v:.6f}".rstrip("0")
            decimals = max(decimals, len(text.split(".")[1]))
    return min(decimals, 6)


class ParameterForm(QtWidgets.QWidget):
    """The editors of one algorithm's parameters, in spec order.

    Signals
    -------
    changed()
        Any value changed.
    """

    changed = pyqtSignal()

    def __init__(self, algorithm: Algorithm, parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self.algorithm = algorithm
        self._editors: Dict[str, _Editor] = {}
        self._labels: Dict[str, QtWidgets.QLabel] = {}
        layout = QtWidgets.QFormLayout(self)
        layout.setFieldGrowthPolicy(QtWidgets.QFormLayout.AllNonFixedFieldsGrow)
        layout.setLabelAlignment(QtCore.Qt.AlignRight | QtCore.Qt.AlignVCenter)
        layout.setHorizontalSpacing(12)
        layout.setVerticalSpacing(8)
        for p in algorithm.parameters:
            editor = _make_editor(p, self)
            label = QtWidgets.QLabel(self._label_text(p), self)
            label.setToolTip(self._tooltip(p))
            label.setWordWrap(True)  # long descriptions must not squeeze the editors
            label.setMaximumWidth(240)
            font = QtGui.QFont(label.font())
            font.setBold(p.required)
            natural = QtGui.QFontMetrics(font).boundingRect(tr(p.description)).width() + 20
            label.setMinimumWidth(min(natural, 240))  # short labels never wrap
            label.setAlignment(QtCore.Qt.AlignRight | QtCore.Qt.AlignVCenter)
            editor.widget.setToolTip(self._tooltip(p))
            editor.widget.setObjectName(f"param_{p.name}")
            label.setBuddy(editor.widget)
            layout.addRow(label, editor.widget)
            editor.changed.connect(self.changed)
            self._editors[p.name] = editor
            self._labels[p.name] = label
        self._project_params = [p.name for p in algorithm.parameters if p.is_project]
        self._timer = QtCore.QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(300)
        self._timer.timeout.connect(self.update_from_project)
        for name in self._project_params:
            self._editors[name].changed.connect(self._timer.start)

    # -- labels ----------------------------------------------------------------------------------
    @staticmethod
    def _label_text(p: Parameter) -> str:
        text = tr(p.description)
        if p.required:
            return f"<b>{text}</b>"
        return text

    @staticmethod
    def _tooltip(p: Parameter) -> str:
        parts = [tr(p.help) if p.help else tr(p.description)]
        details = [p.flag, p.kind]
        if p.unit:
            details.append(p.unit)
        if p.minimum is not None or p.maximum is not None:
            low = "" if p.minimum is None else f"{p.minimum:g}"
            high = "" if p.maximum is None else f"{p.maximum:g}"
            details.append(f"{low}…{high}")
        details.append(tr("required") if p.required else tr("optional"))
        parts.append(" · ".join(details))
        return "\n".join(parts)

    # -- values ----------------------------------------------------------------------------------
    def editor(self, name: str) -> QtWidgets.QWidget:
        """The editor widget of a parameter (for tests and focus handling)."""
        return self._editors[name].widget

    def values(self) -> Dict[str, Any]:
        """The raw parameter dict; empty fields are left out (defaults then apply)."""
        values = {}
        for name, editor in self._editors.items():
            value = editor.get()
            if value is not None:
                values[name] = value
        return values

    def set_values(self, values: Dict[str, Any]) -> None:
        """Fill editors from a raw parameter dict (unknown names are ignored)."""
        for name, value in values.items():
            if name in self._editors:
                self._editors[name].put(value)
        self.update_from_project()

    # -- remembering -----------------------------------------------------------------------------
    def remember(self, settings: Any) -> None:
        """Store the current raw values under ``PhotoDEM/params/<algorithm>`` (JSON) in a
        ``QSettings``-like object, and the project as the last project."""
        if settings is None:
            return
        values = self.values()
        settings.setValue(SETTINGS_PARAMS + self.algorithm.id, json.dumps(values, default=str))
        project = self.project()
        if project:
            settings.setValue(SETTINGS_PROJECT, project)

    def restore(self, settings: Any) -> bool:
        """Fill the editors with the values remembered for this algorithm (if any)."""
        if settings is None:
            return False
        text = settings.value(SETTINGS_PARAMS + self.algorithm.id, "")
        try:
            values = json.loads(text) if text else None
        except (TypeError, ValueError):  # a damaged setting: start from the defaults
            values = None
        if not isinstance(values, dict):
            return False
        self.set_values(values)
        return True

    def carry_over(self, other: ParameterForm) -> None:
        """Take the inputs of another algorithm's form that this one has too (same name and
        kind; the project, models, images and input files, not outputs or options):
        switching algorithms keeps the project and the input."""
        mine = {p.name: p for p in self.algorithm.parameters}
        values = other.values()
        keep = {}
        for p in other.algorithm.parameters:
            twin = mine.get(p.name)
            if twin is not None and twin.kind == p.kind and (p.is_path or p.is_item_name) \
                    and not p.is_output and p.name in values:
                keep[p.name] = values[p.name]
        if keep:
            self.set_values(keep)

    def project(self) -> Optional[str]:
        """The project folder of the form ('' / None when it has none)."""
        if not self._project_params:
            return None
        return self._editors[self._project_params[0]].get()

    # -- project-driven combos ------------------------------------------------------------------
    def update_from_project(self) -> None:
        """Fill the model/image combos from the project named in the form, if it loads."""
        combos = [(p, self._editors[p.name].widget) for p in self.algorithm.parameters
                  if p.is_item_name]
        if not combos or not self._project_params:
            return
        path = self._editors[self._project_params[0]].get()
        names: Dict[str, List[str]] = {"model": [], "image": []}
        if path and ((Path(path) / "project.toml").is_file()
                     or (path.endswith(".toml") and Path(path).is_file())):
            try:
                project = Project.load(path)
                names = {"model": [m.name for m in project.models],
                         "image": [i.name for i in project.images]}
            except Exception:  # an unreadable project: leave the combos free to type in
                names = {"model": [], "image": []}
        for p, combo in combos:
            current = combo.currentText()
            combo.blockSignals(True)
            combo.clear()
            combo.addItems(names[p.kind])
            if current:
                combo.setEditText(current)
            elif names[p.kind]:
                combo.setCurrentIndex(0)
            combo.blockSignals(False)
            combo.lineEdit().setPlaceholderText(
                tr("type a name") if names[p.kind] or not path else tr("no project found"))
        self.changed.emit()
