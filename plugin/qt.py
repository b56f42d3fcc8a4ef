"""The one Qt import shim of PhotoDEM.

Inside QGIS, Qt comes from ``qgis.PyQt`` (QGIS's own binding switch); outside (standalone tool,
tier-A tests) from PyQt5. Every other module imports Qt only from here::

    from ..qt import QtCore, QtWidgets, QCoreApplication, pyqtSignal

"Inside QGIS" means ``qgis.core`` is already imported by the time this module loads: then mixing
bindings would be fatal, so we must follow QGIS. (Not just ``qgis``: a folder ``tests/qgis`` on
``sys.path`` is importable as a namespace package of that name.) When PyQt5 is missing we fall
back to ``qgis.PyQt`` as well.
"""

from __future__ import annotations

import sys

if "qgis.core" in sys.modules:  # loaded by QGIS (desktop, qgis_process, tier-B tests)
    from qgis.PyQt import QtCore, QtGui, QtSvg, QtWidgets

    BINDING = "qgis.PyQt"
else:
    try:
        from PyQt5 import QtCore, QtGui, QtSvg, QtWidgets

        BINDING = "PyQt5"
    except ImportError:  # pragma: no cover - a QGIS Python without PyQt5 on the path
        from qgis.PyQt import QtCore, QtGui, QtSvg, QtWidgets

        BINDING = "qgis.PyQt"

# The names the plugin and the standalone tool use most; anything else via the modules.
Qt = QtCore.Qt
QCoreApplication = QtCore.QCoreApplication
QLocale = QtCore.QLocale
QObject = QtCore.QObject
QSettings = QtCore.QSettings
QThread = QtCore.QThread
QTimer = QtCore.QTimer
QTranslator = QtCore.QTranslator
QUrl = QtCore.QUrl
pyqtSignal = QtCore.pyqtSignal  # noqa: N816 (Qt's name)
pyqtSlot = QtCore.pyqtSlot  # noqa: N816
QIcon = QtGui.QIcon
QPixmap = QtGui.QPixmap
QAction = QtWidgets.QAction
QApplication = QtWidgets.QApplication
QMenu = QtWidgets.QMenu
QMessageBox = QtWidgets.QMessageBox
QWidget = QtWidgets.QWidget

__all__ = [
    "BINDING",
    "QAction",
    "QApplication",
    "QCoreApplication",
    "QIcon",
    "QLocale",
    "QMenu",
    "QMessageBox",
    "QObject",
    "QPixmap",
    "QSettings",
    "QThread",
    "QTimer",
    "QTranslator",
    "QUrl",
    "QWidget",
    "Qt",
    "QtCore",
    "QtGui",
    "QtSvg",
    "QtWidgets",
    "pyqtSignal",
    "pyqtSlot",
]
