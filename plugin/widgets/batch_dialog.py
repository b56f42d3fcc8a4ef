"""The batch dialog: run steps over the stereo models of a project (standalone tool and QGIS).

The dialog shows the project's stereo models (name, kind, B/H, overlap and the state of each
per-model step from earlier batches) with check boxes, the steps to run and their choices (from
the algorithms' specs), the workers and an optional Dask scheduler (empty: this machine). *Run*
writes the batch file of these choices into
``<project>/.photodem/batches/`` and runs it with the existing runner (:func:`run_batch`: same
state folder, lock and resume rules as ``photodem batch FILE``) off the GUI thread; *Resume*
runs the current batch file again (tasks complete from an earlier run are skipped); *Open batch
file…* loads any batch file, also one over image files (``files = [...]``).

While a batch runs, every model (image, file, or step without items) has a row with a progress
bar and its state; a failure shows its one-line reason; double-clicking a row opens its log.
Closing the dialog while a batch runs asks whether to cancel it or keep it running in the
background (the dialog then only hides). After the run the products are listed with *Open* /
*Show in folder* (QGIS adds them to the workspace) and failed models can be run again alone.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

from ...algorithms.errors import Message, PhotodemError
from ...algorithms.processing import batch, batch_setup
from ...algorithms.processing.batch_setup import BatchChoices
from ..i18n import error_text, tr
from ..qt import QSettings, Qt, QtCore, QtGui, QtWidgets, QUrl, pyqtSignal
from .batch_runner import BatchWorker
from .parameter_form import SETTINGS_PROJECT, PathEdit
from .worker import start_in_thread

#: Settings keys (``QSettings`` standalone, ``QgsSettings`` in QGIS: the same API).
SETTINGS_PREFIX = "PhotoDEM/batch/"

#: Table columns.
COL_MODEL, COL_KIND, COL_BH, COL_OVERLAP, COL_EPI, COL_MATCH, COL_PROGRESS, COL_STATE = range(8)
_STATE_COLOURS = {"done": "#1e7d32", "skipped": "#1e7d32", "failed": "#c0392b",
                  "cancelled": "#b35c00", "running": "#1f5fa8"}
#: What the close question may answer.
CLOSE_CANCEL, CLOSE_BACKGROUND, CLOSE_STAY = "cancel", "background", "stay"


def state_text(state: str) -> str:
    """The translated name of a task / step state."""
    return {"done": tr("done"), "failed": tr("failed"), "not run": tr("not run"),
            "skipped": tr("skipped"), "cancelled": tr("cancelled"), "running": tr("running"),
            "waiting": tr("waiting")}.get(state, state)


def record_error(record: Dict[str, Any]) -> str:
    """A failed task's error in the operator's language (its ``error_message``), else the
    record's English ``error``."""
    data = record.get("error_message")
    message = Message.from_dict(data) if isinstance(data, dict) else None
    return error_text(str(record.get("error") or ""), message)


class _Row:
    """The run state of one table row: its tasks (by index) and their fractions."""

    def __init__(self, row: int) -> None:
        self.row = row
        self.tasks: List[int] = []
        self.fraction: Dict[int, float] = {}
        self.records: Dict[int, Dict[str, Any]] = {}
        self.current: Optional[int] = None  # the task running (or run last)


class BatchDialog(QtWidgets.QDialog):
    """Run a batch over a project's stereo models (or a batch file over images / files).

    Parameters
    ----------
    project : str or Path, optional
        The project to open; default: the project used last.
    settings : QSettings-like, optional
        Where choices are remembered (``QgsSettings`` in QGIS); default ``QSettings()``.
    start_worker : callable, optional
        ``start_worker(worker) -> handle`` runs :meth:`BatchWorker.run` off the GUI thread;
        default a QThread (QGIS passes a QgsTask starter). The handle may have ``wait(ms)``.
    on_products : callable, optional
        Called with the product paths after a run (QGIS: add them to the workspace).

    Signals
    -------
    batch_started(str)
        The batch file that runs.
    batch_finished(object)
        The summary dict (``None`` when the batch could not start).
    backgrounded()
        The operator closed the dialog and chose to keep the batch running.
    """

    batch_started = pyqtSignal(str)
    batch_finished = pyqtSignal(object)
    backgrounded = pyqtSignal()

    def __init__(self, project: Any = None, parent: Optional[QtWidgets.QWidget] = None,
                 settings: Any = None, start_worker: Optional[Callable[[BatchWorker], Any]] = None,
                 on_products: Optional[Callable[[List[str]], None]] = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(tr("Batch over stereo models"))
        self.setObjectName("PhotoDEMBatchDialog")
        self.settings = settings if settings is not None else QSettings()
        self.start_worker = start_worker
        self.on_products = on_products
        #: Opens a URL (file or folder); tests replace it.
        self.open_url: Callable[[QUrl], Any] = QtGui.QDesktopServices.openUrl
        #: Answers the close question (one of CLOSE_*); tests replace it.
        self.ask_close: Callable[[], str] = self._ask_close
        #: Shows an operator message; tests replace it.
        self.report: Callable[[str], None] = self._report
        self.batch_file: Optional[Path] = None
        self.opened_file = False  # the batch file was opened, not written from the choices
        self.summary: Optional[Dict[str, Any]] = None
        self.products: List[str] = []
        self.worker: Optional[BatchWorker] = None
        self._handle: Any = None
        self._plan: Optional[batch.BatchPlan] = None
        self._rows: Dict[str, _Row] = {}
        self._task_rows: Dict[int, _Row] = {}
        self._t0 = 0.0
        self._fraction = 0.0
        self._build()
        self._restore()
        start = project if project is not None else self.settings.value(SETTINGS_PROJECT, "")
        if start:
            self.project_edit.setText(str(start))
        self._timer = QtCore.QTimer(self)
        self._timer.setInterval(500)
        self._timer.timeout.connect(self._tick)

    # -- building --------------------------------------------------------------------------------
    def _build(self) -> None:
        self.project_edit = PathEdit("folder", parent=self)
        self.project_edit.line_edit.setPlaceholderText(tr("project folder (with project.toml)"))
        self.open_button = QtWidgets.QPushButton(tr("Open batch file…"), self)
        top = QtWidgets.QHBoxLayout()
        top.addWidget(QtWidgets.QLabel(tr("Project"), self))
        top.addWidget(self.project_edit, 1)
        top.addWidget(self.open_button)

        self.table = QtWidgets.QTableWidget(0, 8, self)
        self.table.setHorizontalHeaderLabels([
            tr("Model"), tr("Kind"), tr("B/H"), tr("Overlap"), tr("Epipolar pair"),
            tr("Matching"), tr("Progress"), tr("State")])
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        self.table.verticalHeader().setVisible(False)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.setToolTip(tr("Double-click a row to open its log."))
        self.table.cellDoubleClicked.connect(lambda row, _col: self.open_log(row))

        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(self.table, 3)
        layout.addWidget(self._build_steps())  # its natural height: every choice visible
        layout.addWidget(self._build_run_view(), 2)
        layout.addLayout(self._build_buttons())
        self.resize(980, 760)
        self.project_edit.text_changed.connect(self._on_project_text)
        self.open_button.clicked.connect(lambda _c=False: self.open_batch_file())

    def _build_steps(self) -> QtWidgets.QGroupBox:
        box = QtWidgets.QGroupBox(tr("Steps"), self)
        grid = QtWidgets.QGridLayout(box)
        self.step_checks: Dict[str, QtWidgets.QCheckBox] = {}
        labels = {"epipolar_pair": tr("Epipolar pair"), "match_model": tr("Matching"),
                  "dsm_merge": tr("Merge DSMs"),
                  "refine_object_space": tr("Refine in object space"),
                  "filter": tr("DTM filter"), "ortho": tr("Orthophotos")}
        for row, step in enumerate(batch_setup.STEP_ORDER):
            check = QtWidgets.QCheckBox(labels[step], box)
            check.setObjectName(f"step_{step}")
            self.step_checks[step] = check
            grid.addWidget(check, row // 2, (row % 2) * 3)
        self.method_combo = _combo(box, batch_setup.choice_options("match_model", "method"))
        self.match_preset = _combo(box, batch_setup.choice_options("match_model", "preset"),
                                   default=batch_setup.choice_default("match_model", "preset"))
        self.filter_combo = _combo(box, batch_setup.FILTERS, names=True)
        self.filter_preset = _combo(box, batch_setup.choice_options("filter_lowpass", "preset"),
                                    default=batch_setup.choice_default("filter_lowpass",
                                                                       "preset"))
        self.ortho_combo = _combo(box, batch_setup.ORTHO_STEPS, names=True)
        for combo, tip in ((self.method_combo, tr("Matching method")),
                           (self.match_preset, tr("Matching preset")),
                           (self.filter_combo, tr("DTM filter")),
                           (self.filter_preset, tr("Filter preset")),
                           (self.ortho_combo, tr("Single orthophotos or a mosaic"))):
            combo.setToolTip(tip)
        grid.addWidget(self.method_combo, 0, 4)  # beside Matching
        grid.addWidget(self.match_preset, 0, 5)
        grid.addWidget(self.filter_combo, 2, 1)
        grid.addWidget(self.filter_preset, 2, 2)
        grid.addWidget(self.ortho_combo, 2, 4)
        self.workers_spin = QtWidgets.QSpinBox(box)
        self.workers_spin.setRange(1, 64)
        self.workers_spin.setValue(batch_setup.default_workers())
        self.workers_spin.setToolTip(tr("Worker processes (default: cores − 1)"))
        grid.addWidget(QtWidgets.QLabel(tr("Workers"), box), 3, 0)
        grid.addWidget(self.workers_spin, 3, 1)
        self.scheduler_edit = QtWidgets.QLineEdit(box)
        self.scheduler_edit.setObjectName("scheduler")
        self.scheduler_edit.setPlaceholderText(tr("empty = this machine"))
        self.scheduler_edit.setToolTip(tr(
            "Address of a Dask scheduler (tcp://host:8786) whose workers run the batch; the "
            "project must be on storage every worker sees at the same path."))
        grid.addWidget(QtWidgets.QLabel(tr("Scheduler"), box), 3, 2)
        grid.addWidget(self.scheduler_edit, 3, 3, 1, 3)
        self.file_label = QtWidgets.QLabel(box)
        self.file_label.setWordWrap(True)
        self.file_label.setTextInteractionFlags(Qt.TextSelectableByMouse)
        grid.addWidget(self.file_label, 4, 0, 1, 6)
        self.steps_box = box
        return box

    def _build_run_view(self) -> QtWidgets.QWidget:
        self.progress_bar = QtWidgets.QProgressBar(self)
        self.progress_bar.setRange(0, 1000)
        self.progress_bar.setFormat("%p %")
        self.time_label = QtWidgets.QLabel(self)
        self.log_view = QtWidgets.QPlainTextEdit(self)
        self.log_view.setReadOnly(True)
        self.log_view.setMaximumBlockCount(5000)
        self.log_view.setFont(QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont))
        self.log_view.setPlaceholderText(tr("The log of the batch appears here."))
        self.product_list = QtWidgets.QListWidget(self)
        self.product_list.itemDoubleClicked.connect(lambda item: self.open_product(item.text()))
        self.product_open = QtWidgets.QPushButton(tr("Open"), self)
        self.product_folder = QtWidgets.QPushButton(tr("Show in folder"), self)
        self.product_open.clicked.connect(lambda _c=False: self._open_selected(False))
        self.product_folder.clicked.connect(lambda _c=False: self._open_selected(True))
        products = QtWidgets.QWidget(self)
        p_layout = QtWidgets.QVBoxLayout(products)
        p_layout.setContentsMargins(0, 0, 0, 0)
        p_layout.addWidget(self.product_list, 1)
        p_buttons = QtWidgets.QHBoxLayout()
        p_buttons.addWidget(self.product_open)
        p_buttons.addWidget(self.product_folder)
        p_buttons.addStretch(1)
        p_layout.addLayout(p_buttons)
        self.tabs = QtWidgets.QTabWidget(self)
        self.tabs.addTab(self.log_view, tr("Log"))
        self.tabs.addTab(products, tr("Products"))
        view = QtWidgets.QWidget(self)
        v_layout = QtWidgets.QVBoxLayout(view)
        v_layout.setContentsMargins(0, 0, 0, 0)
        line = QtWidgets.QHBoxLayout()
        line.addWidget(self.progress_bar, 1)
        line.addWidget(self.time_label)
        v_layout.addLayout(line)
        v_layout.addWidget(self.tabs, 1)
        return view

    def _build_buttons(self) -> QtWidgets.QHBoxLayout:
        self.run_button = QtWidgets.QPushButton(tr("Run"), self)
        self.run_button.setDefault(True)
        self.run_button.setToolTip(tr("Write the batch file of these choices and run it"))
        self.resume_button = QtWidgets.QPushButton(tr("Resume"), self)
        self.resume_button.setToolTip(tr("Run the batch file again; finished tasks are skipped"))
        self.rerun_button = QtWidgets.QPushButton(tr("Re-run failed"), self)
        self.cancel_button = QtWidgets.QPushButton(tr("Cancel"), self)
        self.close_button = QtWidgets.QPushButton(tr("Close"), self)
        buttons = QtWidgets.QHBoxLayout()
        buttons.addWidget(self.rerun_button)
        buttons.addStretch(1)
        for b in (self.cancel_button, self.resume_button, self.run_button, self.close_button):
            buttons.addWidget(b)
        self.run_button.clicked.connect(lambda _c=False: self.run())
        self.resume_button.clicked.connect(lambda _c=False: self.resume())
        self.rerun_button.clicked.connect(lambda _c=False: self.rerun_failed())
        self.cancel_button.clicked.connect(lambda _c=False: self.cancel())
        self.close_button.clicked.connect(self.close)
        self._update_buttons()
        return buttons

    # -- remembering -----------------------------------------------------------------------------
    def _restore(self) -> None:
        value = self.settings.value(SETTINGS_PREFIX + "steps", None)
        steps = [value] if isinstance(value, str) else list(value or ["epipolar_pair",
                                                                      "match_model"])
        for step, check in self.step_checks.items():
            check.setChecked(step in steps)
        for key, combo in self._combos().items():
            value = self.settings.value(SETTINGS_PREFIX + key, None)
            if value is not None and combo.findData(value) >= 0:
                combo.setCurrentIndex(combo.findData(value))
        workers = self.settings.value(SETTINGS_PREFIX + "workers", None)
        if workers not in (None, ""):
            self.workers_spin.setValue(int(workers))
        self.scheduler_edit.setText(str(self.settings.value(SETTINGS_PREFIX + "scheduler", "")
                                        or ""))
        geometry = self.settings.value(SETTINGS_PREFIX + "geometry", None)
        if isinstance(geometry, QtCore.QByteArray):
            self.restoreGeometry(geometry)

    def _remember(self) -> None:
        s = self.settings
        s.setValue(SETTINGS_PREFIX + "steps", [k for k, c in self.step_checks.items()
                                               if c.isChecked()])
        for key, combo in self._combos().items():
            s.setValue(SETTINGS_PREFIX + key, combo.currentData())
        s.setValue(SETTINGS_PREFIX + "workers", self.workers_spin.value())
        s.setValue(SETTINGS_PREFIX + "scheduler", self.scheduler())
        s.setValue(SETTINGS_PREFIX + "geometry", self.saveGeometry())
        if self.project_folder() is not None:
            s.setValue(SETTINGS_PROJECT, str(self.project_folder()))

    def _combos(self) -> Dict[str, QtWidgets.QComboBox]:
        return {"method": self.method_combo, "match_preset": self.match_preset,
                "filter": self.filter_combo, "filter_preset": self.filter_preset,
                "ortho": self.ortho_combo}

    # -- the project -----------------------------------------------------------------------------
    def project_folder(self) -> Optional[Path]:
        """The project folder of the field, if it holds a project.toml."""
        text = self.project_edit.text().strip()
        if text and (Path(text) / "project.toml").is_file():
            return Path(text).resolve()
        return None

    def _on_project_text(self, _text: str) -> None:
        if self.is_running():
            return
        self.opened_file = False
        self.batch_file = None
        self.load_models()

    def load_models(self) -> None:
        """Fill the table with the project's models and their states from earlier runs."""
        folder = self.project_folder()
        self.table.setRowCount(0)
        self._rows = {}
        self.steps_box.setEnabled(True)
        if folder is None:
            self.file_label.setText(tr("Choose a project folder, or open a batch file."))
            self._update_buttons()
            return
        try:
            rows = batch_setup.model_rows(folder)
        except PhotodemError as exc:
            self.file_label.setText(tr("The project cannot be read: {0}").format(error_text(exc)))
            self._update_buttons()
            return
        for model in rows:
            self._add_row(model.name, model.kind, model.b_h, model.overlap, model.states)
        self.table.resizeColumnsToContents()
        self.file_label.setText(tr("Run writes the batch file into {0}").format(
            folder / batch_setup.BATCH_FOLDER))
        self._update_buttons()

    def _add_row(self, name: str, kind: str, b_h: Optional[float] = None,
                 overlap: Optional[float] = None, states: Optional[Dict[str, str]] = None,
                 checked: bool = True) -> int:
        row = self.table.rowCount()
        self.table.insertRow(row)
        item = QtWidgets.QTableWidgetItem(name)
        item.setFlags(item.flags() | Qt.ItemIsUserCheckable)
        item.setCheckState(Qt.Checked if checked else Qt.Unchecked)
        self.table.setItem(row, COL_MODEL, item)
        self.table.setItem(row, COL_KIND, QtWidgets.QTableWidgetItem(tr(kind)))
        self.table.setItem(row, COL_BH, _number_item(b_h, "{:.2f}"))
        self.table.setItem(row, COL_OVERLAP, _number_item(
            None if overlap is None else overlap * 100, "{:.0f} %"))
        for col, step in ((COL_EPI, "epipolar_pair"), (COL_MATCH, "match_model")):
            state = (states or {}).get(step, "")
            self.table.setItem(row, col, _state_item(state))
        bar = QtWidgets.QProgressBar(self.table)
        bar.setRange(0, 1000)
        bar.setValue(0)
        bar.setFormat("%p %")
        bar.setTextVisible(False)  # until the row is part of a run
        self.table.setCellWidget(row, COL_PROGRESS, bar)
        self.table.setItem(row, COL_STATE, QtWidgets.QTableWidgetItem(""))
        self._rows[name] = _Row(row)
        return row

    def checked_models(self) -> List[str]:
        """The models checked in the table."""
        names = []
        for row in range(self.table.rowCount()):
            item = self.table.item(row, COL_MODEL)
            if item is not None and item.checkState() == Qt.Checked:
                names.append(item.text())
        return names

    def set_checked_models(self, names: List[str]) -> None:
        """Check exactly the models in ``names``."""
        for row in range(self.table.rowCount()):
            item = self.table.item(row, COL_MODEL)
            item.setCheckState(Qt.Checked if item.text() in names else Qt.Unchecked)

    def scheduler(self) -> str:
        """The Dask scheduler's address as typed (empty: this machine)."""
        return self.scheduler_edit.text().strip()

    def choices(self) -> BatchChoices:
        """The operator's choices as :class:`BatchChoices`."""
        folder = self.project_folder()
        if folder is None:
            raise PhotodemError(tr("Choose a project folder (with project.toml) first."))
        return BatchChoices(
            project=folder, models=self.checked_models(),
            steps=[s for s, c in self.step_checks.items() if c.isChecked()],
            workers=self.workers_spin.value(), method=self.method_combo.currentData(),
            match_preset=self.match_preset.currentData(),
            filter=self.filter_combo.currentData(),
            filter_preset=self.filter_preset.currentData(),
            ortho=self.ortho_combo.currentData(), scheduler=self.scheduler() or None)

    # -- batch files -----------------------------------------------------------------------------
    def open_batch_file(self, path: Optional[str] = None) -> bool:
        """Open an existing batch file (asks for it unless given); *Run* then runs it as it
        is. Returns whether it could be read."""
        if path is None:
            start = str(self.project_folder() or Path.home())
            path = QtWidgets.QFileDialog.getOpenFileName(
                self, tr("Open batch file"), start, tr("Batch files (*.toml)"))[0]
            if not path:
                return False
        try:
            plan = batch.load_batch(path)
        except PhotodemError as exc:
            self.report(tr("The batch file cannot be used: {0}").format(error_text(exc)))
            return False
        self.project_edit.blockSignals(True)
        self.project_edit.setText(str(plan.project or ""))
        self.project_edit.blockSignals(False)
        if plan.project is not None:
            self.load_models()
        else:
            self.table.setRowCount(0)
            self._rows = {}
        self.workers_spin.setValue(plan.workers)
        self.scheduler_edit.setText(plan.scheduler or "")
        self._rows_from_plan(plan, check=True)
        self.batch_file = Path(path).resolve()
        self.opened_file = True
        self.steps_box.setEnabled(True)
        self._set_steps_enabled(False)
        self._show_file()
        self._update_buttons()
        return True

    def _set_steps_enabled(self, enabled: bool) -> None:
        for widget in [*self.step_checks.values(), *self._combos().values()]:
            widget.setEnabled(enabled)

    def _show_file(self) -> None:
        if self.batch_file is not None:
            self.file_label.setText(tr("Batch file: {0}\nRun it again with: photodem batch "
                                       "{0}").format(self.batch_file))

    def write_batch_file(self) -> Path:
        """Write the batch file of the current choices and make it the current one."""
        path = batch_setup.write_batch(self.choices())
        self.batch_file, self.opened_file = path, False
        self._show_file()
        return path

    # -- running ---------------------------------------------------------------------------------
    def is_running(self) -> bool:
        return self.worker is not None

    def run(self) -> bool:
        """Run: the opened batch file as it is, or a new one written from the choices."""
        if self.is_running():
            return False
        try:
            if not self.opened_file:
                self.write_batch_file()
        except PhotodemError as exc:
            self.report(error_text(exc))
            return False
        self._remember()
        return self._start(self.batch_file)

    def resume(self) -> bool:
        """Run the current batch file again: tasks complete from an earlier run are skipped."""
        if self.is_running() or self.batch_file is None:
            return False
        return self._start(self.batch_file)

    def rerun_failed(self) -> bool:
        """Run the current batch file again for the failed models/images alone (and the steps
        without items); the rest of the file is not run, complete tasks are skipped."""
        if self.is_running() or self.summary is None or self.batch_file is None:
            return False
        failed = batch_setup.failed_items(self.summary)
        if not failed:
            return False
        return self._start(self.batch_file, only=failed)

    def _start(self, path: Optional[Path], only: Optional[List[str]] = None) -> bool:
        if path is None:
            return False
        self.summary, self.products = None, []
        self.product_list.clear()
        self.log_view.clear()
        self.tabs.setCurrentIndex(0)
        self.progress_bar.setValue(0)
        worker = BatchWorker(path, workers=self.workers_spin.value(), only=only,
                             scheduler=self.scheduler())
        worker.planned.connect(self._on_planned)
        worker.progress.connect(self._on_progress)
        worker.task_progress.connect(self._on_task_progress)
        worker.task_finished.connect(self._on_task_finished)
        worker.log.connect(self._append_log)
        worker.finished.connect(self._on_finished)
        worker.failed.connect(self._on_failed)
        worker.done.connect(self._on_done)
        self.worker = worker
        self._t0, self._fraction = time.monotonic(), 0.0
        self._timer.start()
        self._append_log("info", tr("Running batch file {0} …").format(path))
        if self.start_worker is not None:
            self._handle = self.start_worker(worker)
        else:
            self._handle = start_in_thread(worker)
        self._update_buttons()
        self.batch_started.emit(str(path))
        return True

    def cancel(self) -> None:
        """Ask the running batch to stop; running tasks discard their staged outputs."""
        if self.worker is not None:
            self.worker.cancel()
            self.cancel_button.setEnabled(False)
            self._append_log("warning", tr("Cancelling …"))

    def wait(self, msecs: int = 60000) -> bool:
        """Block until the batch thread ended (tests, closing the application)."""
        handle = self._handle
        if handle is None or not hasattr(handle, "wait"):
            return True
        try:
            return bool(handle.wait(msecs))
        except RuntimeError:  # already deleted
            return True

    # -- progress --------------------------------------------------------------------------------
    def _on_planned(self, plan: batch.BatchPlan) -> None:
        self._plan = plan
        self._rows_from_plan(plan, check=False)

    def _rows_from_plan(self, plan: batch.BatchPlan, check: bool) -> None:
        """Map every task to a row: its model/image/file, or its step (new rows as needed)."""
        self._task_rows = {}
        for row in self._rows.values():
            row.tasks, row.fraction, row.records, row.current = [], {}, {}, None
        names = []
        for task in plan.tasks:
            name = task.name if task.item is not None else task.step
            if name not in self._rows:
                kind = task.item_kind or task.algorithm
                self._add_row(name, kind)
            row = self._rows[name]
            row.tasks.append(task.index)
            row.fraction[task.index] = 0.0
            self._task_rows[task.index] = row
            names.append(name)
            self._set_state(row, "waiting")
            self._bar(row).setValue(0)
            self._bar(row).setTextVisible(True)
        if check:
            self.set_checked_models(names)

    def _bar(self, row: _Row) -> QtWidgets.QProgressBar:
        return self.table.cellWidget(row.row, COL_PROGRESS)

    def _set_state(self, row: _Row, state: str, detail: str = "") -> None:
        item = self.table.item(row.row, COL_STATE)
        text = state_text(state) + (f": {detail}" if detail else "")
        item.setText(text)
        item.setToolTip(text)
        colour = _STATE_COLOURS.get(state)
        item.setForeground(QtGui.QBrush(QtGui.QColor(colour)) if colour else QtGui.QBrush())

    def _on_progress(self, pct: float) -> None:
        self._fraction = pct / 100.0
        self.progress_bar.setValue(round(pct * 10))

    def _on_task_progress(self, index: int, pct: float) -> None:
        row = self._task_rows.get(index)
        if row is None or self._plan is None:
            return
        row.current = index
        row.fraction[index] = pct / 100.0
        self._bar(row).setValue(round(1000 * sum(row.fraction.values()) / len(row.tasks)))
        self._set_state(row, "running", f"{self._plan.tasks[index].step} {pct:.0f} %")

    def _on_task_finished(self, index: int, record: Dict[str, Any]) -> None:
        row = self._task_rows.get(index)
        if row is None:
            return
        row.records[index] = record
        row.current = index
        status = record.get("status", "")
        if status in ("done", "skipped", "failed"):
            row.fraction[index] = 1.0
        self._bar(row).setValue(round(1000 * sum(row.fraction.values()) / len(row.tasks)))
        self._show_row_state(row)
        task = self._plan.tasks[index] if self._plan is not None else None
        if task is not None and task.item_kind == "model":
            col = {"epipolar_pair": COL_EPI, "match_model": COL_MATCH}.get(task.algorithm)
            if col is not None and status in ("done", "skipped", "failed"):
                self.table.setItem(row.row, col, _state_item(
                    "done" if status == "skipped" else status))

    def _show_row_state(self, row: _Row) -> None:
        """A row's state: failed (with the reason) > running > cancelled > done/skipped."""
        statuses = [row.records.get(i, {}).get("status") for i in row.tasks]
        failed = [row.records[i] for i in row.tasks
                  if row.records.get(i, {}).get("status") == "failed"]
        if failed:
            reason = record_error(failed[0]).strip().splitlines()
            self._set_state(row, "failed", reason[0] if reason else "")
        elif any(s is None for s in statuses):
            if not self.is_running():
                self._set_state(row, "cancelled")
            else:  # its next task waits for the step before it
                self._set_state(row, "waiting")
        elif "cancelled" in statuses:
            self._set_state(row, "cancelled")
        else:
            self._set_state(row, "done" if "done" in statuses else "skipped")

    def _tick(self) -> None:
        elapsed = time.monotonic() - self._t0
        remaining = batch_setup.remaining_seconds(elapsed, self._fraction)
        self.time_label.setText(tr("elapsed {0} · remaining {1}").format(
            batch_setup.format_seconds(elapsed), batch_setup.format_seconds(remaining)))

    def _append_log(self, level: str, message: str) -> None:
        prefix = {"warning": tr("Warning: "), "error": tr("Error: ")}.get(level, "")
        self.log_view.appendPlainText(f"{time.strftime('%H:%M:%S')} {prefix}{message}")

    # -- the end ---------------------------------------------------------------------------------
    def _on_finished(self, summary: Dict[str, Any]) -> None:
        self.summary = summary
        for row in self._rows.values():
            if row.tasks:
                self._show_row_state(row)
        counts = ", ".join(f"{v} {state_text(k)}" for k, v in summary["counts"].items() if v)
        self._append_log("info", tr("Batch {0}: {1}; summary in {2}").format(
            state_text(summary["status"]), counts, summary["summary"]))
        self.products = batch_setup.summary_products(summary)
        for path in self.products:
            item = QtWidgets.QListWidgetItem(path)
            item.setToolTip(path)
            self.product_list.addItem(item)
        if self.products:
            self.tabs.setCurrentIndex(1)
        if self.on_products is not None and self.products:
            self.on_products(list(self.products))

    def _on_failed(self, message: str) -> None:
        self._append_log("error", message)
        self.report(message)

    def _on_done(self) -> None:
        self._timer.stop()
        self._tick()
        self.worker, self._handle = None, None
        self._update_buttons()
        self.batch_finished.emit(self.summary)
        if self.project_folder() is not None and not self.opened_file:
            self._refresh_states()

    def _refresh_states(self) -> None:
        """The step columns from the resume state (what the next run would skip)."""
        folder = self.project_folder()
        states = batch_setup.step_states(folder, list(self._rows))
        for name, row in self._rows.items():
            for col, step in ((COL_EPI, "epipolar_pair"), (COL_MATCH, "match_model")):
                if (step, name) in states or self.table.item(row.row, col).text():
                    self.table.setItem(row.row, col, _state_item(
                        states.get((step, name), "not run")))

    def _update_buttons(self) -> None:
        running = self.is_running()
        self.run_button.setEnabled(not running and (self.project_folder() is not None
                                                    or self.opened_file))
        self.resume_button.setEnabled(not running and self.batch_file is not None)
        self.cancel_button.setEnabled(running)
        self.rerun_button.setEnabled(not running and self.summary is not None
                                     and bool(batch_setup.failed_items(self.summary)))
        self.open_button.setEnabled(not running)
        self.project_edit.setEnabled(not running)
        self._set_steps_enabled(not running and not self.opened_file)
        self.workers_spin.setEnabled(not running)
        self.scheduler_edit.setEnabled(not running)

    # -- opening logs and products ---------------------------------------------------------------
    def open_log(self, row_number: int) -> Optional[str]:
        """Open the log of the task that runs (or ran last) in a row; its path, if any."""
        row = next((r for r in self._rows.values() if r.row == row_number), None)
        if row is None or self._plan is None or not row.tasks:
            return None
        index = row.current if row.current is not None else row.tasks[0]
        log = Path(self._plan.tasks[index].log)
        if not log.is_file():
            self.report(tr("No log yet: the task has not started."))
            return None
        self.open_url(QUrl.fromLocalFile(str(log)))
        return str(log)

    def open_product(self, path: str, folder: bool = False) -> None:
        """Open a product (or its folder) with the system's application."""
        target = Path(path).parent if folder else Path(path)
        self.open_url(QUrl.fromLocalFile(str(target)))

    def _open_selected(self, folder: bool) -> None:
        item = self.product_list.currentItem() or self.product_list.item(0)
        if item is not None:
            self.open_product(item.text(), folder)

    # -- closing ---------------------------------------------------------------------------------
    def _ask_close(self) -> str:
        box = QtWidgets.QMessageBox(self)
        box.setIcon(QtWidgets.QMessageBox.Question)
        box.setWindowTitle(tr("Batch is running"))
        box.setText(tr("The batch is still running. Cancel it, or keep it running in the "
                       "background?"))
        cancel = box.addButton(tr("Cancel the batch"), QtWidgets.QMessageBox.DestructiveRole)
        keep = box.addButton(tr("Keep running"), QtWidgets.QMessageBox.AcceptRole)
        box.addButton(tr("Back"), QtWidgets.QMessageBox.RejectRole)
        box.setDefaultButton(keep)
        box.exec_()
        clicked = box.clickedButton()
        return CLOSE_CANCEL if clicked is cancel else CLOSE_BACKGROUND if clicked is keep \
            else CLOSE_STAY

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:
        self._remember()
        if not self.is_running():
            super().closeEvent(event)
            return
        answer = self.ask_close()
        if answer == CLOSE_CANCEL:
            self.cancel()
            super().closeEvent(event)
        elif answer == CLOSE_BACKGROUND:
            event.ignore()
            self.hide()
            self.backgrounded.emit()
        else:
            event.ignore()

    def reject(self) -> None:
        """Escape closes like the window's close button (asking when a batch runs)."""
        self.close()

    def _report(self, text: str) -> None:
        QtWidgets.QMessageBox.warning(self, tr("PhotoDEM"), text)


def _combo(parent: QtWidgets.QWidget, options: Any, names: bool = False,
           default: Any = None) -> QtWidgets.QComboBox:
    """A combo of spec options (translated labels, the option as data), on ``default``."""
    combo = QtWidgets.QComboBox(parent)
    for option in options:
        label = option if names else tr(option)
        combo.addItem(label, option)
    if default is not None and combo.findData(default) >= 0:
        combo.setCurrentIndex(combo.findData(default))
    return combo


def _number_item(value: Optional[float], fmt: str) -> QtWidgets.QTableWidgetItem:
    text = "" if value is None or value != value else fmt.format(value)
    item = QtWidgets.QTableWidgetItem(text)
    item.setTextAlignment(int(Qt.AlignRight | Qt.AlignVCenter))
    return item


def _state_item(state: str) -> QtWidgets.QTableWidgetItem:
    item = QtWidgets.QTableWidgetItem(state_text(state) if state else "")
    colour = _STATE_COLOURS.get(state)
    if colour:
        item.setForeground(QtGui.QBrush(QtGui.QColor(colour)))
    return item


__all__ = ["CLOSE_BACKGROUND", "CLOSE_CANCEL", "CLOSE_STAY", "BatchDialog", "state_text"]
