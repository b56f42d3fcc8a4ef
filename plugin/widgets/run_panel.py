"""Run / Cancel buttons, a progress bar, the log pane and the result of a run."""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

from ..i18n import error_text, tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal
from .worker import AlgorithmWorker, start_in_thread

#: Item data role of a result row that names an existing file or folder.
PATH_ROLE = QtCore.Qt.UserRole + 7
#: File endings the map shows as rasters and as vectors (``.json`` only as ``.geo.json``).
RASTER_SUFFIXES = (".tif", ".tiff", ".vrt", ".img", ".jp2")
VECTOR_SUFFIXES = (".gpkg", ".shp", ".geojson", ".fgb", ".kml")
_LEVEL_COLOURS = {"info": None, "warning": "#b35c00", "error": "#c0392b", "ok": "#1e7d32"}


class RunPanel(QtWidgets.QWidget):
    """Starts :class:`AlgorithmWorker` runs and shows their progress, log and outputs.

    Signals
    -------
    run_requested()
        The Run button was pressed (the owner collects the parameters and calls :meth:`start`).
    run_finished(str, object)
        ``(status, payload)`` with status ``done`` (payload: output dict), ``failed``
        (message, in the operator's language), ``cancelled`` (message).
    show_on_map(str)
        *Show on map* of an output raster or vector (its path).
    """

    run_requested = pyqtSignal()
    run_finished = pyqtSignal(str, object)
    show_on_map = pyqtSignal(str)

    def __init__(self, parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self._worker: Optional[AlgorithmWorker] = None
        self._thread: Optional[QtCore.QThread] = None
        self._status = ""
        self._payload: Any = None
        self.algorithm_id = ""

        self.run_button = QtWidgets.QPushButton(tr("Run"), self)
        self.run_button.setDefault(True)
        self.run_button.setIcon(self.style().standardIcon(QtWidgets.QStyle.SP_MediaPlay))
        self.cancel_button = QtWidgets.QPushButton(tr("Cancel"), self)
        self.cancel_button.setIcon(self.style().standardIcon(QtWidgets.QStyle.SP_BrowserStop))
        self.cancel_button.setEnabled(False)
        self.progress_bar = QtWidgets.QProgressBar(self)
        self.progress_bar.setRange(0, 1000)
        self.progress_bar.setValue(0)
        self.progress_bar.setFormat("%p %")
        self.progress_bar.setTextVisible(True)

        self.log_view = QtWidgets.QPlainTextEdit(self)
        self.log_view.setReadOnly(True)
        self.log_view.setMaximumBlockCount(5000)
        self.log_view.setPlaceholderText(tr("The log of the run appears here."))
        font = QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont)
        self.log_view.setFont(font)
        self.result_view = QtWidgets.QTreeWidget(self)
        self.result_view.setColumnCount(3)
        self.result_view.setHeaderLabels([tr("Output"), tr("Value"), ""])
        self.result_view.setRootIsDecorated(True)
        self.result_view.setAlternatingRowColors(True)
        header = self.result_view.header()
        header.setStretchLastSection(False)
        header.setSectionResizeMode(1, QtWidgets.QHeaderView.Stretch)
        header.setSectionResizeMode(2, QtWidgets.QHeaderView.ResizeToContents)
        self.result_view.itemDoubleClicked.connect(
            lambda item, _col: self.open_path(item.data(1, PATH_ROLE) or ""))
        #: Opens a file or folder URL with the system's application; tests replace it.
        self.open_url: Callable[[QtCore.QUrl], Any] = QtGui.QDesktopServices.openUrl
        self.report_button = QtWidgets.QPushButton(tr("Open report"), self)
        self.report_button.setEnabled(False)
        self.report_button.clicked.connect(lambda _c=False: self.open_report())
        result_page = QtWidgets.QWidget(self)
        result_layout = QtWidgets.QVBoxLayout(result_page)
        result_layout.setContentsMargins(0, 0, 0, 0)
        result_layout.addWidget(self.result_view, 1)
        report_line = QtWidgets.QHBoxLayout()
        report_line.addStretch(1)
        report_line.addWidget(self.report_button)
        result_layout.addLayout(report_line)
        self.result_page = result_page

        self.tabs = QtWidgets.QTabWidget(self)
        self.tabs.addTab(self.log_view, tr("Log"))
        self.tabs.addTab(result_page, tr("Result"))

        buttons = QtWidgets.QHBoxLayout()
        buttons.addWidget(self.progress_bar, 1)
        buttons.addWidget(self.cancel_button)
        buttons.addWidget(self.run_button)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(buttons)
        layout.addWidget(self.tabs, 1)

        self.run_button.clicked.connect(self.run_requested)
        self.cancel_button.clicked.connect(self.cancel)

    # -- state -----------------------------------------------------------------------------------
    def is_running(self) -> bool:
        return self._worker is not None

    @property
    def status(self) -> str:
        """Status of the last run: '', 'running', 'done', 'failed', 'cancelled'."""
        return self._status

    @property
    def result(self) -> Any:
        return self._payload

    # -- running ---------------------------------------------------------------------------------
    def start(self, algorithm_id: str, params: Dict[str, Any]) -> AlgorithmWorker:
        """Run ``algorithm_id`` with raw ``params`` in a worker thread."""
        if self.is_running():
            raise RuntimeError("a run is already going on")
        self.algorithm_id = algorithm_id
        self.result_view.clear()
        self.progress_bar.setValue(0)
        self.tabs.setCurrentWidget(self.log_view)
        self.append_log("ok", tr("Running {0} …").format(algorithm_id))
        self.append_log("info", json.dumps(params, ensure_ascii=False, default=str))
        worker = AlgorithmWorker(algorithm_id, params)
        worker.progress.connect(self._on_progress)
        worker.log.connect(self.append_log)
        worker.finished.connect(self._on_finished)
        worker.failed.connect(self._on_failed)
        worker.cancelled.connect(self._on_cancelled)
        self._worker = worker
        self._status = "running"
        self._payload = None
        self.run_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        # The panel owns the thread: dropping the Python reference to a thread that is still
        # winding down would destroy it while it runs, which aborts the process. The run counts
        # as finished only once the thread has ended, so a new run can start right away.
        self._thread = start_in_thread(worker, on_finished=self._on_done)
        return worker

    def cancel(self) -> None:
        """Ask the running algorithm to stop; it discards its staged outputs."""
        if self._worker is not None:
            self._worker.cancel()
            self.cancel_button.setEnabled(False)
            self.append_log("warning", tr("Cancelling …"))

    def wait(self, msecs: int = 30000) -> bool:
        """Block until the worker thread ended (used when the window closes)."""
        thread = self._thread
        if thread is None:
            return True
        try:
            return bool(thread.wait(msecs))
        except RuntimeError:  # already deleted
            return True

    # -- slots -----------------------------------------------------------------------------------
    def _on_progress(self, pct: float) -> None:
        self.progress_bar.setValue(round(pct * 10))

    def append_log(self, level: str, message: str) -> None:
        colour = _LEVEL_COLOURS.get(level)
        text = html.escape(message).replace("\n", "<br>")
        if level == "warning":
            text = tr("Warning: ") + text
        if colour:
            text = f'<span style="color:{colour}">{text}</span>'
        self.log_view.appendHtml(text)

    def _on_finished(self, result: Dict[str, Any]) -> None:
        self._status, self._payload = "done", result
        self.progress_bar.setValue(1000)
        self.show_result(result)
        self.append_log("ok", tr("Finished."))

    def _on_failed(self, message: str, operator_error: bool, parts: Any = None) -> None:
        if operator_error:
            message = error_text(message, parts)
            self.append_log("error", tr("Error: ") + message)
        else:
            self.append_log("error", tr("Unexpected error (please report it):") + "\n" + message)
        self._status, self._payload = "failed", message

    def _on_cancelled(self, message: str) -> None:
        self._status, self._payload = "cancelled", message
        self.progress_bar.setValue(0)
        self.append_log("warning", message)

    def _on_done(self) -> None:
        self._worker = self._thread = None
        self.run_button.setEnabled(True)
        self.cancel_button.setEnabled(False)
        self.run_finished.emit(self._status, self._payload)

    def show_result(self, result: Dict[str, Any]) -> None:
        """Show an output dict as a tree (nested dicts and lists expand); every output that is
        an existing file or folder gets *Open* and *Show in folder*, a raster or vector also
        *Show on map*."""
        self.result_view.clear()
        for key, value in result.items():
            self.result_view.addTopLevelItem(_tree_item(str(key), value))
        self.result_view.expandToDepth(0)
        for i in range(self.result_view.topLevelItemCount()):
            item = self.result_view.topLevelItem(i)
            item.setExpanded(item.childCount() <= 6)  # long tables stay folded: files in view
        iterator = QtWidgets.QTreeWidgetItemIterator(self.result_view)
        while iterator.value():
            item = iterator.value()
            path = item.data(1, PATH_ROLE)
            if path:
                self.result_view.setItemWidget(item, 2, self._path_buttons(path))
            iterator += 1
        self.result_view.resizeColumnToContents(0)
        self.report_button.setEnabled(self.report_path() is not None)
        self.tabs.setCurrentWidget(self.result_page)

    def _path_buttons(self, path: str) -> QtWidgets.QWidget:
        box = QtWidgets.QWidget(self.result_view)
        layout = QtWidgets.QHBoxLayout(box)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setSpacing(2)
        if is_map_file(path):
            button = QtWidgets.QToolButton(box)
            button.setText(tr("Show on map"))
            button.setObjectName("showOnMap")
            button.setAutoRaise(True)
            button.clicked.connect(lambda _c=False: self.show_on_map.emit(path))
            layout.addWidget(button)
        for text, folder in ((tr("Open"), False), (tr("Show in folder"), True)):
            button = QtWidgets.QToolButton(box)
            button.setText(text)
            button.setAutoRaise(True)
            button.clicked.connect(lambda _c=False, f=folder: self.open_path(path, f))
            layout.addWidget(button)
        layout.addStretch(1)
        return box

    def map_outputs(self) -> List[str]:
        """The outputs of the last result the map can show (rasters, vectors)."""
        return [p for p in self.output_paths() if is_map_file(p)]

    # -- opening outputs -------------------------------------------------------------------------
    def output_paths(self) -> List[str]:
        """The outputs of the last result that are existing files or folders, in order."""
        paths = []
        iterator = QtWidgets.QTreeWidgetItemIterator(self.result_view)
        while iterator.value():
            path = iterator.value().data(1, PATH_ROLE)
            if path:
                paths.append(str(path))
            iterator += 1
        return paths

    def report_path(self) -> Optional[str]:
        """The run's report: an HTML output, else an output named ``report``."""
        result = self._payload if isinstance(self._payload, dict) else {}
        candidates = [v for k, v in result.items() if k in ("report_html", "report")]
        candidates += [p for p in self.output_paths() if p.endswith((".html", ".htm"))]
        for value in sorted(candidates, key=lambda v: not str(v).endswith((".html", ".htm"))):
            if isinstance(value, str) and Path(value).is_file():
                return value
        return None

    def open_path(self, path: str, folder: bool = False) -> bool:
        """Open an output (or the folder that holds it) with the system's application."""
        if not path:
            return False
        target = Path(path)
        if folder and target.is_file():
            target = target.parent
        return bool(self.open_url(QtCore.QUrl.fromLocalFile(str(target))))

    def open_report(self) -> bool:
        """Open the run's report, if it has one."""
        report = self.report_path()
        return self.open_path(report) if report else False


def _tree_item(key: str, value: Any) -> QtWidgets.QTreeWidgetItem:
    if isinstance(value, dict):
        item = QtWidgets.QTreeWidgetItem([key, f"{{{len(value)}}}"])
        for k, v in value.items():
            item.addChild(_tree_item(str(k), v))
    elif isinstance(value, list) and value and isinstance(value[0], (dict, list)):
        item = QtWidgets.QTreeWidgetItem([key, f"[{len(value)}]"])
        for i, v in enumerate(value):
            item.addChild(_tree_item(str(i), v))
    else:
        text = json.dumps(value, ensure_ascii=False) if isinstance(value, list) else str(value)
        item = QtWidgets.QTreeWidgetItem([key, text])
        item.setToolTip(1, text)
        if isinstance(value, str) and len(value) > 1 and _is_path(value):
            item.setData(1, PATH_ROLE, value)
    return item


def is_map_file(path: str) -> bool:
    """True for an existing file the map can show, by its ending."""
    p = Path(path)
    name = p.name.lower()
    return p.is_file() and (name.endswith(RASTER_SUFFIXES + VECTOR_SUFFIXES)
                            or name.endswith(".geo.json"))


def _is_path(text: str) -> bool:
    """An absolute path that exists (an output file or folder)."""
    try:
        path = Path(text)
        return path.is_absolute() and path.exists()
    except (OSError, ValueError):
        return False
