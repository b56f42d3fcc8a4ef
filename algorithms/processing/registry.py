"""The registry of all PhotoDEM algorithms, and the one function that runs them.

Algorithm declarations live in :mod:`.algs` (one module per domain); each module lists its
classes in ``ALGORITHMS``. Every face (QGIS provider, standalone toolbox, CLI, batch) asks this
registry, so adding an algorithm is one class in one module.
"""

from __future__ import annotations

import importlib
import os
import time
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Sequence

from .. import output_policy
from ..errors import InputError, PhotodemError
from ..feedback import Feedback, ensure_feedback
from ..input_errors import check_raster_parameters, operator_errors
from ..jsonable import json_ready
from .spec import Algorithm, prepare_parameters, project_files

#: Modules below ``algorithms/processing/algs`` that declare algorithms, in toolbox order.
ALGORITHM_MODULES = (
    "project",
    "synthetic",
    "geometry",
    "quality",
    "matching",
    "surface",
    "filtering",
    "ortho",
    "georef",
)

#: Comma-separated importable modules with further ``ALGORITHMS`` (site extensions, tests).
EXTRA_MODULES_ENV = "PHOTODEM_EXTRA_ALGORITHMS"

_CACHE: Dict[str, Algorithm] = {}


def algorithms() -> Dict[str, Algorithm]:
    """All algorithms by id, in declaration order (built-in ones, then extra modules)."""
    if not _CACHE:
        for module_name in ALGORITHM_MODULES:
            module = importlib.import_module(f"{__package__}.algs.{module_name}")
            for cls in module.ALGORITHMS:
                alg = cls()
                if alg.id in _CACHE:
                    raise RuntimeError(f"duplicate algorithm id {alg.id!r}")
                _CACHE[alg.id] = alg
        add_modules(extra_modules())
    return dict(_CACHE)


def extra_modules() -> List[str]:
    """Module names from :data:`EXTRA_MODULES_ENV`."""
    return [n.strip() for n in os.environ.get(EXTRA_MODULES_ENV, "").split(",") if n.strip()]


def add(algorithm: Algorithm) -> Algorithm:
    """Register one more algorithm (replacing one with the same id); returns it."""
    algorithms()  # the built-in ones first
    _CACHE[algorithm.id] = algorithm
    return algorithm


def remove(algorithm_id: str) -> None:
    """Unregister an algorithm added with :func:`add` (no error if absent)."""
    _CACHE.pop(algorithm_id, None)


def add_modules(names: Iterable[str]) -> List[str]:
    """Import modules that list ``ALGORITHMS`` and register them; returns their ids."""
    ids = []
    for name in (n.strip() for n in names if n and n.strip()):
        module = importlib.import_module(name)
        for cls in module.ALGORITHMS:
            ids.append(add(cls()).id)
    return ids


def get(algorithm_id: str) -> Algorithm:
    """The algorithm with this id (a ``photodem:`` prefix is accepted).

    Raises
    ------
    InputError
        When no such algorithm exists; the message lists the known ids.
    """
    key = algorithm_id.split(":", 1)[1] if algorithm_id.startswith("photodem:") else algorithm_id
    algs = algorithms()
    if key not in algs:
        raise InputError.of("No algorithm '{algorithm}'. Known algorithms: {known}.",
                            algorithm=algorithm_id, known=", ".join(algs))
    return algs[key]


def run(
    algorithm_id: str,
    params: Dict[str, Any],
    feedback: Optional[Feedback] = None,
) -> Dict[str, Any]:
    """Run an algorithm from raw parameter values and return its JSON-ready outputs.

    This is the single entry point of every face: parameters are checked and converted by
    :func:`~.spec.prepare_parameters`, every output the run will write is checked against the
    output policy (:func:`check_outputs`) and stale staging leftovers beside it are removed —
    all before the first computation — then the algorithm runs in a run scope that records
    its committed outputs, and its outputs are made JSON-ready. Once an output is committed a
    cancellation no longer raises: the run finishes its product set (the caller sees
    ``feedback.is_canceled()`` and reports a late interrupt).

    Raises
    ------
    PhotodemError
        For anything the operator can fix (including :class:`~..errors.Cancelled`).
    """
    alg = get(algorithm_id)
    feedback = ensure_feedback(feedback)
    with operator_errors(feedback):  # damaged inputs end as one-line operator errors
        prepared = prepare_parameters(alg, params)
        check_raster_parameters(alg.parameters, prepared)  # before any work
        targets = check_outputs(alg, prepared)
        output_policy.remove_stale(_folders_written(targets), feedback.info)
        start = time.perf_counter()
        with output_policy.run_scope(alg.id, feedback.mark_committed, targets):
            result = alg.run(prepared, feedback)
            feedback.progress(100.0)
    feedback.info(f"{alg.id} finished in {time.perf_counter() - start:.1f} s.")
    return json_ready(result)


def check_outputs(alg: Algorithm, prepared: Dict[str, Any],
                  run_folder: Optional[Path] = None) -> List[output_policy.Target]:
    """The outputs a run of ``alg`` with converted ``prepared`` values writes, once checked.

    One check for a run (:func:`run`) and for a batch task while the batch is planned.

    Parameters
    ----------
    alg : Algorithm
        The algorithm.
    prepared : dict
        Its converted parameter values.
    run_folder : Path, optional
        Given while a batch is planned: the resolved run folder, where the batch writes its
        logs; no output may be or contain it. Inputs an earlier step makes need not exist
        then: a ``project`` input that is no project yet counts with its own path only, and an
        output derived from such a project is left to the check when the task runs.

    Raises
    ------
    InputError
        When an output is forbidden (see :mod:`..output_policy`).
    """
    if run_folder is None:
        targets = alg.output_targets(prepared)
        if targets:
            inputs, protected = alg.input_paths(prepared)
            output_policy.check_targets(alg.id, targets, inputs, protected)
        return targets
    return _check_planned_outputs(alg, prepared, run_folder)


def _check_planned_outputs(alg: Algorithm, values: Dict[str, Any],
                           run_folder: Path) -> List[output_policy.Target]:
    """:func:`check_outputs` of a batch task while the batch is planned."""
    projects = [p.name for p in alg.parameters if p.is_project and values.get(p.name)]
    pending = [name for name in projects if not _is_project(values[name])]
    try:
        targets = alg.output_targets(values)
    except PhotodemError:
        if pending:  # derived from a project an earlier step makes: the run checks it
            return []
        raise
    if not targets:
        return targets
    for target in targets:
        out = target.path.resolve()
        if out == run_folder or out in run_folder.parents:
            raise InputError.of("Parameter '{name}': the output '{path}' is or contains the "
                                "run folder '{folder}', where the batch writes its logs; "
                                "choose another output.", name=target.name, path=target.path,
                                folder=run_folder)
    # The project files as Algorithm.input_paths lists them, but listed and resolved once
    # per project, and only those an output is or contains (the only ones compared).
    inputs, protected = alg.input_paths({**values, **dict.fromkeys(projects)})
    outs = [t.path.resolve() for t in targets]
    for name in projects:
        inputs.append(Path(values[name]))
        if name not in pending:
            protected += _covered(project_files(values[name]), outs)
    output_policy.check_targets(alg.id, targets, inputs, protected)
    return targets


def _covered(paths: Sequence[Path], outs: Sequence[Path]) -> List[Path]:
    """The resolved ``paths`` that one of the resolved ``outs`` is or contains (by name: no
    file system calls, which matter for a project of a thousand images and tasks)."""
    prefixes = []
    for out in outs:
        text = os.path.normcase(str(out))
        prefixes.append((text, text if text.endswith(os.sep) else text + os.sep))
    found = []
    for path in paths:
        text = os.path.normcase(str(path))
        if any(text == same or text.startswith(below) for same, below in prefixes):
            found.append(path)
    return found


def _is_project(value: Any) -> bool:
    """True when ``value`` names a project folder (or its ``project.toml``) that exists."""
    path = Path(value)
    file = path / output_policy.PROJECT_FILE if path.is_dir() else path
    return file.is_file()


def _folders_written(targets: Iterable[output_policy.Target]) -> List[Path]:
    """The folders a run writes in: each output's parent and every folder output."""
    folders: List[Path] = []
    for t in targets:
        folders.append(t.path.parent)
        if t.kind == "folder":
            folders.append(t.path)
    return folders


def groups() -> List[str]:
    """Group names in toolbox order."""
    seen: List[str] = []
    for alg in algorithms().values():
        if alg.group not in seen:
            seen.append(alg.group)
    return seen
