"""The parameters of the runs offered on a stereo model where the operator sees it on a map.

Both faces offer the same three actions on a stereo model — in QGIS
(``plugin/qgis/model_actions.py``) and in the standalone tool's map: *Match this model…*,
*Epipolar pair* and *Filter its DSM…*. This module builds their raw parameter dicts (as
``registry.run`` takes them) so the two faces fill their forms the same way: the outputs are
written out (the default folders ``products/dsm/<model>`` and ``products/dtm/<model>``) so the
operator sees where the products go.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Union

from ..errors import InputError
from .model import Project

PathLike = Union[str, Path]


class NoDsmYet(InputError):
    """The stereo model has no DSM to filter yet.

    Attributes
    ----------
    model : str
        The stereo model's name.
    dsm : str
        Where its DSM is expected, relative to the project folder.
    """

    def __init__(self, model: str, dsm: str) -> None:
        super().__init__(f"Stereo model {model} has no DSM yet ({dsm}); match it first.")
        self.model = model
        self.dsm = dsm


def _model_of(project_root: PathLike, model: str) -> Project:
    """The loaded project, after checking it holds ``model`` (InputError otherwise)."""
    project = Project.load(project_root)
    project.model(model)
    return project


def match_model_parameters(project_root: PathLike, model: str) -> Dict[str, Any]:
    """The ``match_model`` parameters of one model: project, model, output folder.

    Parameters
    ----------
    project_root : str or Path
        The project folder (or its ``project.toml``); passed on as given.
    model : str
        The stereo model's name.

    Returns
    -------
    dict
        ``{"project", "model", "output"}``; the output is ``products/dsm/<model>``.

    Raises
    ------
    InputError
        The project does not load or has no such model.
    """
    project = _model_of(project_root, model)
    return {"project": str(project_root), "model": model,
            "output": str(project.products_dir("dsm") / model)}


def epipolar_pair_parameters(project_root: PathLike, model: str) -> Dict[str, Any]:
    """The ``epipolar_pair`` parameters of one model (its default output folder is kept).

    Raises
    ------
    InputError
        The project does not load or has no such model.
    """
    _model_of(project_root, model)
    return {"project": str(project_root), "model": model}


def model_dsm(project: Project, model: str) -> Path:
    """Where ``match_model`` writes the DSM of ``model`` by default."""
    return project.products_dir("dsm") / model / "dsm.tif"


def filter_dsm_parameters(project_root: PathLike, model: str) -> Dict[str, Any]:
    """The ``filter_lowpass`` parameters that filter the DSM of one model to its DTM.

    Returns
    -------
    dict
        ``{"input", "project", "output"}``: the model's ``products/dsm/<model>/dsm.tif`` and
        the output folder ``products/dtm/<model>``.

    Raises
    ------
    NoDsmYet
        The model has not been matched yet (no DSM in its default place).
    InputError
        The project does not load or has no such model.
    """
    project = _model_of(project_root, model)
    dsm = model_dsm(project, model)
    if not dsm.is_file():
        raise NoDsmYet(model, project.relative_path(dsm))
    return {"input": str(dsm), "project": str(project_root),
            "output": str(project.products_dir("dtm") / model)}


__all__ = ["NoDsmYet", "epipolar_pair_parameters", "filter_dsm_parameters",
           "match_model_parameters", "model_dsm"]
