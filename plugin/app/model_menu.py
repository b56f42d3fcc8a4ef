"""Run from the map: the context menu of the stereo models under a right click, and the open
project in the toolbox's forms (the standalone side of ``plugin/qgis/model_actions.py``).

A right press on the map that the active tool does not use (``MapView.context_menu_requested``)
opens a menu with one sub-menu per stereo model under the click:

* *Match this model…* — the ``match_model`` form in the toolbox, project, model and output folder
  filled in (it does not run);
* *Epipolar pair* — runs ``epipolar_pair`` of the model through the run panel (the Run button's
  path: a worker thread, its outputs on the map when done);
* *Filter its DSM…* — the ``filter_lowpass`` form with the model's DSM (a status-bar message
  when the model has none yet).

The parameters come from :mod:`photodem.algorithms.project.model_runs`, as in QGIS.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

from shapely.geometry import Point

from ...algorithms.errors import PhotodemError
from ...algorithms.processing.spec import Algorithm
from ...algorithms.project.model_runs import (
    NoDsmYet,
    epipolar_pair_parameters,
    filter_dsm_parameters,
    match_model_parameters,
)
from ..i18n import error_text, tr
from ..qt import QtCore, QtWidgets

#: The map layer kind of the stereo models (as in QGIS's workspace).
STEREO_MODELS_KIND = "stereo_models"
#: How close (in pixels) a click must come to a model's outline to count as on it.
PICK_PIXELS = 3.0

#: A handler of an entry: model name → what it opened or started.
Handler = Callable[[str], Any]


def default_values(algorithm: Algorithm) -> Dict[str, Any]:
    """Every parameter at its default (empty where it has none) — a form with nothing left
    from an earlier run (a remembered output folder of another model must not be reused)."""
    values: Dict[str, Any] = {}
    for p in algorithm.parameters:
        if p.default is not None:
            values[p.name] = p.default
        elif not (p.is_numeric and not p.optional) and not p.is_bool:
            values[p.name] = ""
    return values


def fill_project(form: Any, root: str) -> bool:
    """Put ``root`` into the form's project parameter (its first); False if it has none."""
    params = getattr(form, "_project_params", None) if form is not None else None
    if not params:
        return False
    form.set_values({params[0]: root})
    return True


def _project_folder(path: str) -> Path:
    """The folder of a project given as its folder or its ``project.toml``."""
    folder = Path(path)
    return (folder.parent if folder.suffix.lower() == ".toml" else folder).resolve()


def prefer_map_project(form: Any, root: str) -> None:
    """Give a newly shown form the map's project. Values remembered for another project
    (its models, inputs, output folders) are dropped: they belong to that project."""
    current = form.project() if form is not None else None
    if current and _project_folder(current) != _project_folder(root):
        form.set_values(default_values(form.algorithm))
    fill_project(form, root)


class ModelMenu(QtCore.QObject):
    """The stereo-model actions of the standalone window's map.

    Parameters
    ----------
    window : ToolboxWindow
        The main window: ``map_view``, ``project_root``, ``select_algorithm``, ``run_current``,
        ``run_panel``, ``toolbox_dock``, ``statusBar()``.
    """

    def __init__(self, window: Any) -> None:
        super().__init__(window)
        self.window = window
        #: The menu of the last right click (tests pick its entries).
        self.menu: Optional[QtWidgets.QMenu] = None
        window.map_view.context_menu_requested.connect(self.show_menu)
        window.project_opened.connect(self.project_opened)

    # -- the open project in the forms ------------------------------------------------------------
    def project_opened(self, root: str) -> None:
        """The current form works on the project just opened on the map."""
        fill_project(self.window.form, root)

    # -- the menu ---------------------------------------------------------------------------------
    def entries(self) -> List[Tuple[str, Handler]]:
        """The actions as (label, handler), in menu order (the labels of QGIS's menu)."""
        return [(tr("Match this model…"), self.match_model),
                (tr("Epipolar pair"), self.epipolar_pair),
                (tr("Filter its DSM…"), self.filter_dsm)]

    def models_at(self, x: float, y: float) -> List[str]:
        """The names of the stereo models under the map point (sorted); none without a
        project or when the stereo-models layer is hidden."""
        layer = self.window.map_view.layer_by_kind(STEREO_MODELS_KIND)
        if layer is None or not layer.visible or self.window.project_root is None:
            return []
        tolerance = PICK_PIXELS * self.window.map_view.map_units_per_pixel()
        point = Point(x, y)
        names = {str(attributes.get("name", fid)) for fid, geometry, attributes
                 in layer.features() if geometry is not None and not geometry.is_empty
                 and geometry.distance(point) <= tolerance}
        return sorted(names)

    def build_menu(self, x: float, y: float) -> Optional[QtWidgets.QMenu]:
        """The menu for a right click at the map point: a sub-menu per model under it."""
        models = self.models_at(x, y)
        if not models:
            return None
        menu = QtWidgets.QMenu(self.window)
        for model in models:
            sub = menu.addMenu(tr("Stereo model {0}").format(model))
            for text, handler in self.entries():
                action = sub.addAction(text)
                action.triggered.connect(lambda _=False, h=handler, m=model: h(m))
        self.menu = menu
        return menu

    def show_menu(self, x: float, y: float, global_pos: QtCore.QPoint) -> None:
        """Open the menu of the models under a right click (nothing when there is none)."""
        menu = self.build_menu(x, y)
        if menu is not None:
            menu.exec_(QtCore.QPoint(global_pos))

    # -- the actions ------------------------------------------------------------------------------
    def _root(self) -> str:
        return str(self.window.project_root)

    def show_form(self, algorithm_id: str, params: Dict[str, Any]) -> Any:
        """Show the form of ``algorithm_id`` in the toolbox: defaults, then ``params``."""
        window = self.window
        form = window.select_algorithm(algorithm_id)
        form.set_values({**default_values(form.algorithm), **params})
        window.toolbox_dock.show()
        window.toolbox_dock.raise_()
        return form

    def match_model(self, model: str) -> Any:
        """Show the ``match_model`` form with project, model and output folder (no run)."""
        try:
            params = match_model_parameters(self._root(), model)
        except PhotodemError as exc:
            self.window.report(error_text(exc))
            return None
        return self.show_form("match_model", params)

    def epipolar_pair(self, model: str) -> Any:
        """Run ``epipolar_pair`` of the model through the run panel (its form shown)."""
        window = self.window
        if window.run_panel.is_running():
            window.report(tr("A run is going on; wait until it has finished."), warning=False)
            return None
        try:
            params = epipolar_pair_parameters(self._root(), model)
        except PhotodemError as exc:
            window.report(error_text(exc))
            return None
        form = self.show_form("epipolar_pair", params)
        window.run_current()
        return form

    def filter_dsm(self, model: str) -> Any:
        """Show the ``filter_lowpass`` form for the model's DSM (a message if it has none)."""
        try:
            params = filter_dsm_parameters(self._root(), model)
        except NoDsmYet as exc:
            self.window.report(tr("Stereo model {0} has no DSM yet ({1}); match it "
                                  "first.").format(exc.model, exc.dsm), warning=False)
            return None
        except PhotodemError as exc:
            self.window.report(error_text(exc))
            return None
        return self.show_form("filter_lowpass", params)


__all__ = ["ModelMenu", "default_values", "fill_project", "prefer_map_project"]
