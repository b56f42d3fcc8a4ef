"""Start the standalone toolbox (``photodem gui`` or ``python -m photodem.plugin.app.main``)."""

from __future__ import annotations

import sys
from typing import List, Optional

from ..i18n import install_translator
from ..qt import QtCore, QtWidgets

_windows: list = []
#: Who the toolbox is to ``QSettings`` (its settings file).
ORGANIZATION = "PhotoDEM"
APPLICATION = "PhotoDEM toolbox"


def main(argv: Optional[List[str]] = None, project: Optional[str] = None) -> int:
    """Create the application (or reuse a running one), show the toolbox (with ``project``
    open on the map when given), run the event loop."""
    argv = list(sys.argv if argv is None else argv)
    app = QtWidgets.QApplication.instance()
    owns_app = app is None
    if owns_app:
        app = QtWidgets.QApplication(argv)
        app.setOrganizationName(ORGANIZATION)
        app.setApplicationName(APPLICATION)
    install_translator()  # German when the system locale is German and i18n/*.qm exists

    # lazy: imported after the translator is installed, so labels are translated once
    from .main_window import ToolboxWindow

    # named settings, not the application's names: a running application (a host, a test
    # session) is not renamed, else every later ToolboxWindow() of it would read and write
    # these settings too
    window = ToolboxWindow(settings=QtCore.QSettings(ORGANIZATION, APPLICATION))
    _windows.append(window)  # keep a reference when the caller runs the event loop
    window.show()
    if project:
        window.open_project(project)  # a bad path is reported in the window, not raised
    if not owns_app:
        return 0
    return int(app.exec_())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
