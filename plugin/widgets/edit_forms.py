"""The small dialogs of the editing tools: a height, an exclusion action, breakline heights.

Qt only (no QGIS import): the QGIS toolbar and the standalone map share them. Each dialog has a
plain function that opens it modally and returns the answer (``None`` when the operator
cancels). The map tools call them through :class:`DialogAsker`, which tests replace
by a stand-in with the same methods so that no dialog blocks a test.
"""

from __future__ import annotations

import math
from typing import Any, List, Optional, Sequence, Tuple

from ...algorithms.project.edits import BREAKLINE_KINDS, EXCLUSION_ACTIONS
from ..i18n import tr
from ..qt import QtWidgets

QComboBox = QtWidgets.QComboBox
QDialog = QtWidgets.QDialog
QDialogButtonBox = QtWidgets.QDialogButtonBox
QDoubleSpinBox = QtWidgets.QDoubleSpinBox
QFormLayout = QtWidgets.QFormLayout
QLabel = QtWidgets.QLabel
QLineEdit = QtWidgets.QLineEdit
QMessageBox = QtWidgets.QMessageBox
QVBoxLayout = QtWidgets.QVBoxLayout

#: Heights the forms accept (m): wide enough for any terrain, narrow enough to catch a typo.
HEIGHT_RANGE = (-1000.0, 9000.0)


def action_labels() -> List[Tuple[str, str]]:
    """The exclusion actions with their translated labels, in the core's order."""
    labels = {"keep": tr("keep (surface stays as measured)"),
              "remove": tr("remove (not matched; bridged in the DTM)"),
              "exclude": tr("exclude (as remove)")}
    return [(value, labels[value]) for value in EXCLUSION_ACTIONS]


def kind_labels() -> List[Tuple[str, str]]:
    """The breakline kinds with their translated labels."""
    labels = {"breakline": tr("breakline"), "structure_line": tr("structure line")}
    return [(value, labels.get(value, value)) for value in BREAKLINE_KINDS]


def height_box(value: Optional[float], parent: Any = None) -> QDoubleSpinBox:
    """A spin box for a height in metres; empty-looking (special text) when ``value`` is None."""
    box = QDoubleSpinBox(parent)
    box.setRange(HEIGHT_RANGE[0] - 0.001, HEIGHT_RANGE[1])
    box.setDecimals(3)
    box.setSuffix(" m")
    box.setSpecialValueText(tr("type a height"))  # shown at the minimum = no value yet
    ok = value is not None and math.isfinite(value)
    box.setValue(float(value) if ok else box.minimum())
    return box


def box_value(box: QDoubleSpinBox) -> Optional[float]:
    """The height of a :func:`height_box`, ``None`` when none was typed."""
    return None if box.value() <= box.minimum() else float(box.value())


class _Form(QDialog):
    """A titled form with a message line and OK/Cancel."""

    def __init__(self, parent: Any, title: str, message: str = "") -> None:
        super().__init__(parent)
        self.setWindowTitle(title)
        self.setObjectName("photodemEditForm")
        layout = QVBoxLayout(self)
        self.message = QLabel(message, self)
        self.message.setWordWrap(True)
        self.message.setVisible(bool(message))
        layout.addWidget(self.message)
        self.form = QFormLayout()
        layout.addLayout(self.form)
        self.buttons = QDialogButtonBox(QDialogButtonBox.Ok | QDialogButtonBox.Cancel, self)
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        layout.addWidget(self.buttons)


class HeightDialog(_Form):
    """A height (pre-filled with the sampled one, or empty to type) and a text field."""

    def __init__(self, parent: Any, title: str, height: Optional[float], message: str = "",
                 text_label: str = "", text: str = "") -> None:
        super().__init__(parent, title, message)
        self.height = height_box(height, self)
        self.height.setObjectName("height")
        self.form.addRow(tr("Height"), self.height)
        self.text = QLineEdit(text, self)
        self.text.setObjectName("text")
        self.form.addRow(text_label or tr("Note"), self.text)
        self.height.valueChanged.connect(self._update)
        self._update()

    def _update(self) -> None:
        self.buttons.button(QDialogButtonBox.Ok).setEnabled(box_value(self.height) is not None)


class ActionDialog(_Form):
    """The action of a new exclusion area and a note."""

    def __init__(self, parent: Any) -> None:
        super().__init__(parent, tr("Exclusion area"),
                         tr("What should happen inside the area?"))
        self.action = QComboBox(self)
        self.action.setObjectName("action")
        for value, label in action_labels():
            self.action.addItem(label, value)
        self.action.setCurrentIndex(self.action.findData("remove"))
        self.form.addRow(tr("Action"), self.action)
        self.note = QLineEdit(self)
        self.form.addRow(tr("Note"), self.note)


class BreaklineDialog(_Form):
    """Heights of a breakline's vertices (some fixed, some typed) and its kind."""

    def __init__(self, parent: Any, heights: Sequence[Optional[float]],
                 editable: Sequence[bool], message: str = "") -> None:
        super().__init__(parent, tr("Breakline heights"), message)
        self.kind = QComboBox(self)
        self.kind.setObjectName("kind")
        for value, label in kind_labels():
            self.kind.addItem(label, value)
        self.form.addRow(tr("Kind"), self.kind)
        self.boxes: List[QDoubleSpinBox] = []
        for k, (z, free) in enumerate(zip(heights, editable)):
            box = height_box(z, self)
            box.setEnabled(bool(free))
            box.valueChanged.connect(self._update)
            self.boxes.append(box)
            self.form.addRow(tr("Vertex {0}").format(k + 1), box)
        self._update()

    def _update(self) -> None:
        done = all(box_value(b) is not None for b in self.boxes if b.isEnabled())
        self.buttons.button(QDialogButtonBox.Ok).setEnabled(done)

    def heights(self) -> List[Optional[float]]:
        return [box_value(b) for b in self.boxes]


class DialogAsker:
    """The real dialogs, one method per question of the map tools (tests pass a stand-in).

    Parameters
    ----------
    parent : QWidget or None
        The window the dialogs belong to.
    """

    def __init__(self, parent: Any = None) -> None:
        self.parent = parent

    def height(self, title: str, height: Optional[float], message: str = "",
               text_label: str = "") -> Optional[Tuple[float, str]]:
        """A height (pre-filled, editable) and a text; ``None`` when cancelled."""
        dialog = HeightDialog(self.parent, title, height, message, text_label)
        if dialog.exec_() != QDialog.Accepted:
            return None
        return box_value(dialog.height), dialog.text.text().strip()

    def action(self) -> Optional[Tuple[str, str]]:
        """The action of an exclusion area and a note; ``None`` when cancelled."""
        dialog = ActionDialog(self.parent)
        if dialog.exec_() != QDialog.Accepted:
            return None
        return str(dialog.action.currentData()), dialog.note.text().strip()

    def breakline(self, heights: Sequence[Optional[float]], editable: Sequence[bool],
                  message: str = "") -> Optional[Tuple[List[float], str]]:
        """Vertex heights (the editable ones typed) and the kind; ``None`` when cancelled."""
        dialog = BreaklineDialog(self.parent, heights, editable, message)
        if dialog.exec_() != QDialog.Accepted:
            return None
        return [float(z) for z in dialog.heights()], str(dialog.kind.currentData())

    def text(self, title: str, label: str) -> Optional[str]:
        """One line of text (a boundary's name); ``None`` when cancelled."""
        dialog = _Form(self.parent, title)
        edit = QLineEdit(dialog)
        dialog.form.addRow(label, edit)
        if dialog.exec_() != QDialog.Accepted:
            return None
        return edit.text().strip()

    def repair(self, message: str) -> bool:
        """Whether the operator accepts the repaired polygon."""
        answer = QMessageBox.question(self.parent, tr("Invalid polygon"),
                                      message + "\n\n" + tr("Use the repaired polygon?"),
                                      QMessageBox.Yes | QMessageBox.No, QMessageBox.No)
        return answer == QMessageBox.Yes
