"""The stereo-model parameter in Processing dialogs: a drop-down of the chosen project's models.

:class:`ModelWidgetWrapper` is the widget wrapper of every spec parameter of kind ``model``
(:func:`~photodem.plugin.qgis.algorithm.make_parameter` names it in the parameter's metadata).
It follows the dialog's ``project`` parameter and lists that project's stereo models, read with
the core (:meth:`Project.load`). The combo stays editable: a batch row, an unknown project or a
model input of the modeler still take a typed name. In the standard dialog the last project and
model chosen (``QgsSettings`` keys under ``PhotoDEM/``) become the initial values.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from processing.gui.wrappers import DIALOG_BATCH, DIALOG_MODELER, DIALOG_STANDARD, WidgetWrapper
from qgis.core import (
    QgsProcessingContext,
    QgsProcessingOutputString,
    QgsProcessingParameterString,
    QgsSettings,
)
from qgis.PyQt.QtWidgets import QComboBox, QLabel, QSizePolicy, QVBoxLayout, QWidget

from ...algorithms.errors import PhotodemError
from ...algorithms.project.model import Project
from ..i18n import tr

#: Settings keys of the remembered project folder and stereo model.
SETTINGS_PROJECT = "PhotoDEM/last_project"
SETTINGS_MODEL = "PhotoDEM/last_model"
#: Name of the project parameter every model-taking algorithm has.
PROJECT_PARAMETER = "project"

#: Models per project file, keyed by (path, mtime): the combo is refilled on every keystroke
#: of the project path, reading ``project.toml`` each time would be wasteful.
_CACHE: Dict[Tuple[str, float], List[str]] = {}


def project_models(path: Any) -> Tuple[List[str], str]:
    """The stereo-model names of the project at ``path`` and a problem text ('' if none).

    Parameters
    ----------
    path : str or Path or None
        The project folder or its ``project.toml``; empty means "no project chosen".

    Returns
    -------
    (list of str, str)
        The names (empty when the project is missing or unreadable) and a short message
        for the operator (empty when the project was read or none was given).
    """
    text = "" if path is None else str(path).strip()
    if not text:
        return [], ""
    folder = Path(text)
    toml = folder / "project.toml" if folder.is_dir() else folder
    try:
        key = (str(toml.resolve()), toml.stat().st_mtime)
    except OSError:
        # no path in the text: it stands right above, in the project field
        return [], tr("Not a PhotoDEM project: no project.toml in this folder.")
    if key not in _CACHE:
        try:
            _CACHE[key] = [m.name for m in Project.load(toml).models]
        except PhotodemError as exc:
            return [], tr("The project cannot be read: {0}").format(exc)
    return list(_CACHE[key]), ""


def remembered_project() -> str:
    """The project folder chosen last in a PhotoDEM dialog ('' if none)."""
    return str(QgsSettings().value(SETTINGS_PROJECT, "") or "")


def remembered_model() -> str:
    """The stereo model chosen last in a PhotoDEM dialog ('' if none)."""
    return str(QgsSettings().value(SETTINGS_MODEL, "") or "")


def remember(project: Optional[str] = None, model: Optional[str] = None) -> None:
    """Store the project and/or model as the next dialog's initial values."""
    settings = QgsSettings()
    if project:
        settings.setValue(SETTINGS_PROJECT, str(project))
    if model:
        settings.setValue(SETTINGS_MODEL, str(model))


def _text_value(value: Any) -> str:
    """A parameter value as plain text ('' for None, NULL or a list of nothing)."""
    if isinstance(value, (list, tuple)):
        value = value[0] if value else None
    if value is None or type(value).__name__ == "QVariant":
        return ""
    return str(value).strip()


class ModelWidgetWrapper(WidgetWrapper):
    """An editable drop-down of the stereo models of the dialog's project.

    Standard dialog: combo plus a one-line hint under it (shown when the project cannot be
    read); initial values from the remembered project and model. Batch panel: the combo of one
    row, following that row's project. Modeler: an editable combo of the model's string inputs
    (a project is known only at run time there), static text allowed.
    """

    def createWidget(self, **kwargs: Any) -> QWidget:  # noqa: N802 (QGIS API)
        self.combo = QComboBox()
        self.combo.setEditable(True)
        self.combo.setInsertPolicy(QComboBox.NoInsert)
        self.combo.lineEdit().setPlaceholderText(tr("Stereo model name"))
        self.hint: Optional[QLabel] = None
        self.project_wrapper: Any = None
        self._models: List[str] = []
        self._problem = ""
        if self.dialogType == DIALOG_MODELER:
            self._add_model_inputs()
            return self.combo
        self.combo.currentTextChanged.connect(self._model_edited)
        if self.dialogType == DIALOG_BATCH:
            return self.combo
        container = QWidget()
        layout = QVBoxLayout(container)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setSpacing(2)
        layout.addWidget(self.combo)
        self.hint = QLabel()
        self.hint.setObjectName("photodemModelHint")
        self.hint.setWordWrap(True)
        # a long path in a message must wrap, not widen the dialog
        self.hint.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        self.hint.setStyleSheet("color: #a33;")
        self.hint.setVisible(False)
        layout.addWidget(self.hint)
        return container

    def _add_model_inputs(self) -> None:
        """Modeler: offer the model's string inputs and string outputs of earlier steps."""
        dialog = self.dialog
        if not hasattr(dialog, "getAvailableValuesOfType"):
            return
        values = dialog.getAvailableValuesOfType(
            [QgsProcessingParameterString], [QgsProcessingOutputString])
        for value in values:
            self.combo.addItem(dialog.resolveValueDescription(value), value)

    # -- following the project ------------------------------------------------------------------
    def postInitialize(self, wrappers: List[Any]) -> None:  # noqa: N802 (QGIS API)
        """Find the dialog's project parameter, fill in remembered values, list its models."""
        if self.dialogType == DIALOG_MODELER:
            return
        for wrapper in wrappers:
            if wrapper.parameterDefinition().name() == PROJECT_PARAMETER:
                self.project_wrapper = wrapper
                break
        if self.project_wrapper is None:
            return
        if self.dialogType == DIALOG_STANDARD and not self.project_path():
            project = remembered_project()
            if project and project_models(project)[0]:
                self.project_wrapper.setParameterValue(project, QgsProcessingContext())
        self.project_wrapper.widgetValueHasChanged.connect(self._project_changed)
        self.refresh_models()
        if self.dialogType == DIALOG_STANDARD and not self.combo.currentText().strip():
            model = remembered_model()
            self.setValue(model if model in self._models else (self._models or [""])[0])

    def project_path(self) -> str:
        """The project folder currently entered in the dialog ('' if none)."""
        if self.project_wrapper is None:
            return ""
        return _text_value(self.project_wrapper.parameterValue())

    def _project_changed(self, *_args: Any) -> None:
        self.refresh_models()
        if self.dialogType == DIALOG_STANDARD and self._models:
            remember(project=self.project_path())
            if not self.combo.currentText().strip():
                self.setValue(self._models[0])

    def refresh_models(self) -> None:
        """Refill the combo with the current project's models, keeping the typed text."""
        names, problem = project_models(self.project_path())
        current = self.combo.currentText().strip()
        self._models, self._problem = names, problem
        self.combo.blockSignals(True)
        self.combo.clear()
        self.combo.addItems(names)
        self.combo.setCurrentIndex(-1)
        self.combo.setEditText(current)
        if current in names:
            self.combo.setCurrentIndex(names.index(current))
        self.combo.blockSignals(False)
        self.combo.setToolTip(problem or tr("Stereo models of the project"))
        if self.hint is not None:
            self.hint.setText(problem)
            self.hint.setVisible(bool(problem))

    def models(self) -> List[str]:
        """The model names the combo lists now."""
        return list(self._models)

    def hint_text(self) -> str:
        """Why no models are listed ('' when the project was read or none is chosen)."""
        return self._problem

    def _model_edited(self, text: str) -> None:
        if self.dialogType == DIALOG_STANDARD and text.strip() in self._models:
            remember(model=text.strip())
        self.widgetValueHasChanged.emit(self)

    # -- value ----------------------------------------------------------------------------------
    def setValue(self, value: Any) -> None:  # noqa: N802 (QGIS API)
        if self.dialogType == DIALOG_MODELER:
            self.setComboValue(value, self.combo)
            return
        text = _text_value(value)
        index = self.combo.findText(text)
        if index >= 0:
            self.combo.setCurrentIndex(index)
        else:
            self.combo.setEditText(text)

    def value(self) -> Any:
        if self.dialogType == DIALOG_MODELER:
            return self.comboValue(combobox=self.combo)
        text = self.combo.currentText().strip()
        return text or None
