"""*PhotoDEM → Open project…* and the last five projects, and the workspace kept in step with
the QGIS project (a ``.qgz`` read again is bound to its PhotoDEM group).

The recent projects live in ``QgsSettings`` under :data:`RECENT_KEY` (newest first); a project
that has gone is dropped from the list with a message when the operator picks it.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any, List, Optional

from qgis.core import Qgis, QgsProject, QgsSettings
from qgis.PyQt.QtWidgets import QFileDialog, QMenu

from ...algorithms.errors import PhotodemError
from ...algorithms.project.model import PROJECT_FILE
from ..i18n import error_text, tr
from ..qt import QAction
from .workspace import (
    MESSAGE_TITLE,
    Workspace,
    bind_workspace,
    current_workspace,
    forget_workspace,
    open_workspace,
)

#: ``QgsSettings`` key of the recent projects (list of folders, newest first).
RECENT_KEY = "PhotoDEM/recentProjects"
RECENT_COUNT = 5


def recent_projects() -> List[str]:
    """The remembered project folders, newest first (at most :data:`RECENT_COUNT`)."""
    value = QgsSettings().value(RECENT_KEY, [])
    if isinstance(value, str):  # QSettings gives a lone string for a one-item list
        value = [value]
    return [str(v) for v in (value or []) if v][:RECENT_COUNT]


def remember_project(folder: Any) -> List[str]:
    """Put ``folder`` first in the recent projects; returns the new list."""
    folder = str(Path(folder).resolve())
    items = [folder] + [p for p in recent_projects() if p != folder]
    QgsSettings().setValue(RECENT_KEY, items[:RECENT_COUNT])
    return items[:RECENT_COUNT]


def forget_project(folder: str) -> List[str]:
    """Drop ``folder`` from the recent projects; returns the new list."""
    items = [p for p in recent_projects() if p != folder]
    QgsSettings().setValue(RECENT_KEY, items)
    return items


class ProjectMenu:
    """The menu entries *Open project…* and *Recent projects*, and the project signals.

    Parameters
    ----------
    iface : QgisInterface
    menu_title : str
        The plugin menu the entries go to.
    """

    def __init__(self, iface: Any, menu_title: str) -> None:
        self.iface = iface
        self.menu_title = menu_title
        self.open_action: Optional[QAction] = None
        self.recent_menu: Optional[QMenu] = None

    def register(self) -> None:
        """Add the menu entries and follow the QGIS project (read, cleared)."""
        parent = self.iface.mainWindow()
        self.open_action = QAction(tr("Open project…"), parent)
        self.open_action.setObjectName("photodemOpenProject")
        self.open_action.setToolTip(tr("Show a PhotoDEM project on the map: edits, block and "
                                       "products"))
        self.open_action.triggered.connect(lambda _checked=False: self.open_project())
        self.recent_menu = QMenu(tr("Recent projects"), parent)
        self.recent_menu.setObjectName("photodemRecentProjects")
        self.recent_menu.aboutToShow.connect(self.fill_recent_menu)
        self.fill_recent_menu()
        self.iface.addPluginToRasterMenu(self.menu_title, self.open_action)
        self.iface.addPluginToRasterMenu(self.menu_title, self.recent_menu.menuAction())
        QgsProject.instance().readProject.connect(self._project_read)
        QgsProject.instance().cleared.connect(forget_workspace)

    def unregister(self) -> None:
        """Remove the entries and stop following the QGIS project."""
        for signal, slot in ((QgsProject.instance().readProject, self._project_read),
                             (QgsProject.instance().cleared, forget_workspace)):
            with contextlib.suppress(TypeError):  # not connected
                signal.disconnect(slot)
        for action in (self.open_action,
                       self.recent_menu.menuAction() if self.recent_menu else None):
            if action is not None:
                self.iface.removePluginRasterMenu(self.menu_title, action)
        self.open_action = None
        if self.recent_menu is not None:
            self.recent_menu.deleteLater()
            self.recent_menu = None

    def _project_read(self, *_args: Any) -> None:
        bind_workspace(self.iface)

    def fill_recent_menu(self) -> None:
        """One entry per remembered project (refilled each time the menu opens)."""
        menu = self.recent_menu
        menu.clear()
        for folder in recent_projects():
            action = menu.addAction(folder)
            action.triggered.connect(lambda _checked=False, f=folder: self.open_recent(f))
        menu.setEnabled(bool(menu.actions()))

    def open_recent(self, folder: str) -> Optional[Workspace]:
        """Open a remembered project; one that has gone is dropped with a message."""
        if not (Path(folder) / PROJECT_FILE).is_file():
            forget_project(folder)
            self.fill_recent_menu()
            self.iface.messageBar().pushMessage(
                MESSAGE_TITLE, tr("The project {0} is no longer there; it was removed from the "
                                  "recent projects.").format(folder), Qgis.Warning, 8)
            return None
        return self.open_project(folder)

    def ask_project(self) -> Optional[str]:
        """Ask for a ``project.toml`` (file dialog); ``None`` when cancelled."""
        start = recent_projects()[0] if recent_projects() else str(Path.home())
        path, _filter = QFileDialog.getOpenFileName(
            self.iface.mainWindow(), tr("Open PhotoDEM project"), start,
            tr("PhotoDEM project") + f" ({PROJECT_FILE})")
        return path or None

    def open_project(self, path: Any = None) -> Optional[Workspace]:
        """Open a project (asks for it without ``path``) as the workspace; a path that is no
        readable project gives a message-bar error and changes nothing."""
        if path is None:
            path = self.ask_project()
            if path is None:
                return None
        try:
            workspace = open_workspace(self.iface, path)
        except PhotodemError as exc:
            self.iface.messageBar().pushMessage(MESSAGE_TITLE, error_text(exc), Qgis.Critical, 10)
            return None
        remember_project(workspace.root)
        self.fill_recent_menu()
        self.iface.messageBar().pushMessage(
            MESSAGE_TITLE, tr("Project {0} opened.").format(workspace.project.name),
            Qgis.Success, 4)
        return workspace

    @staticmethod
    def current() -> Optional[Workspace]:
        """The current workspace (see :func:`.workspace.current_workspace`)."""
        return current_workspace()
