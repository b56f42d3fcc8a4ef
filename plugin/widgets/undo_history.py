"""The undo history of the edit session (a dock's content) and the Edit menu's Undo/Redo.

The list is Qt's :class:`QtWidgets.QUndoView` of :attr:`EditSession.undo_stack`: a click on an
entry goes back (or forward) to that state; the first row, the state as loaded or last saved,
is called "<empty>" in the operator's language.
"""

from __future__ import annotations

import contextlib
from typing import Any, Optional, Tuple

from ..i18n import tr
from ..qt import QtGui, QtWidgets


def edit_actions(session: Any, parent: QtWidgets.QWidget
                 ) -> Tuple[QtWidgets.QAction, QtWidgets.QAction]:
    """Undo (Ctrl+Z) and Redo (Ctrl+Y, Ctrl+Shift+Z) actions of ``session``'s stack for the
    Edit menu and the toolbar; their texts name the command ("Undo Move vertex")."""
    undo = session.undo_stack.createUndoAction(parent, tr("Undo"))
    redo = session.undo_stack.createRedoAction(parent, tr("Redo"))
    undo.setShortcuts([QtGui.QKeySequence(QtGui.QKeySequence.Undo)])
    redo.setShortcuts([QtGui.QKeySequence("Ctrl+Y"), QtGui.QKeySequence("Ctrl+Shift+Z")])
    undo.setIcon(QtGui.QIcon.fromTheme("edit-undo"))
    redo.setIcon(QtGui.QIcon.fromTheme("edit-redo"))
    undo.setToolTip(tr("Undo the last edit (Ctrl+Z)"))
    redo.setToolTip(tr("Redo the edit undone last (Ctrl+Y)"))
    return undo, redo


class UndoHistory(QtWidgets.QWidget):
    """The list of edits with Undo/Redo buttons (content of the *Undo history* dock).

    Parameters
    ----------
    session : EditSession, optional
        Shown at once; :meth:`set_session` switches to another project's session.
    parent : QWidget, optional
    """

    def __init__(self, session: Any = None,
                 parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self.session: Any = None
        self.view = QtWidgets.QUndoView(self)
        self.view.setEmptyLabel(tr("<empty>"))
        self.undo_button = QtWidgets.QPushButton(tr("Undo"), self)
        self.redo_button = QtWidgets.QPushButton(tr("Redo"), self)
        self.status = QtWidgets.QLabel(self)
        self.status.setWordWrap(True)
        buttons = QtWidgets.QHBoxLayout()
        buttons.addWidget(self.undo_button)
        buttons.addWidget(self.redo_button)
        buttons.addStretch(1)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addWidget(self.view, 1)
        layout.addLayout(buttons)
        layout.addWidget(self.status)
        self.undo_button.clicked.connect(self._undo)
        self.redo_button.clicked.connect(self._redo)
        self.set_session(session)

    def set_session(self, session: Any) -> None:
        """Show the history of ``session`` (``None``: no project open)."""
        if self.session is not None:
            stack = self.session.undo_stack
            for signal, slot in ((stack.canUndoChanged, self.undo_button.setEnabled),
                                 (stack.canRedoChanged, self.redo_button.setEnabled),
                                 (stack.cleanChanged, self._show_status)):
                with contextlib.suppress(TypeError):  # already disconnected
                    signal.disconnect(slot)
        self.session = session
        stack = session.undo_stack if session is not None else None
        self.view.setStack(stack)
        self.undo_button.setEnabled(bool(stack and stack.canUndo()))
        self.redo_button.setEnabled(bool(stack and stack.canRedo()))
        if stack is not None:
            stack.canUndoChanged.connect(self.undo_button.setEnabled)
            stack.canRedoChanged.connect(self.redo_button.setEnabled)
            stack.cleanChanged.connect(self._show_status)
        self._show_status()

    def _undo(self) -> None:
        if self.session is not None:
            self.session.undo_stack.undo()

    def _redo(self) -> None:
        if self.session is not None:
            self.session.undo_stack.redo()

    def _show_status(self, *_: Any) -> None:
        """Read-only, unsaved or saved: one line under the buttons."""
        if self.session is None:
            text = tr("No project open.")
        elif self.session.read_only:
            text = self.session.problem
        elif self.session.dirty:
            text = tr("Unsaved edits.")
        else:
            text = tr("All edits saved.")
        self.status.setText(text)


__all__ = ["UndoHistory", "edit_actions"]
