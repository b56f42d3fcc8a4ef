"""Batch runs: ``photodem batch FILE.toml`` runs algorithms step by step over stereo models.

A batch file is TOML::

    [batch]
    project = "../blocks/ngi"      # project folder (relative to the batch file)
    workers = 2                      # worker processes (1 = run in this process)
    # scheduler = "tcp://10.0.0.5:8786"  # a Dask cluster instead (the CLI's --scheduler wins)
    output = "{project}/runs/night"  # run folder; default <project>/runs/<timestamp>/

    [[steps]]
    algorithm = "epipolar_pair"
    name = "epipolar"                # optional, default: the algorithm id
    models = "all"                   # or ["0182_0184", "0251_0253"]; ``images`` likewise
    [steps.params]
    output = "{project}/products/{step}/{model}"

    [[steps]]                        # a list of image files (no project needed for these)
    algorithm = "georeference_polygons"
    files = ["scenes/*.tif", "extra/LE7_0412.tif"]   # glob patterns or paths
    [steps.params]
    reference = "maps/forest.gpkg"
    output = "{run}/{step}/{file}"

Semantics (kept simple on purpose):

- **Tasks.** A step whose algorithm declares ``iterates_over`` (the name of its ``model`` or
  ``image`` parameter) becomes one task per chosen model/image, with that parameter set; other
  steps are one task. A ``project`` parameter that the step does not set gets the batch project.
- **File lists.** When ``iterates_over`` names a raster or file parameter, the step's ``files``
  (glob patterns or paths, relative to the batch file, sorted) give one task per file. Their
  names (``{file}``, the file name without suffix) must be unique. A batch of such steps needs
  no project: its run folder is then ``runs/<timestamp>/`` and its resume state
  ``.photodem/batch-state.json`` beside the batch file.
- **Paths.** Relative paths in path parameters (inputs and outputs) are relative to the
  batch file's folder, like the paths in ``[batch]``.
- **Placeholders** in parameter strings: ``{project}`` (project folder), ``{run}`` (run folder),
  ``{step}`` (step name), ``{model}`` / ``{image}`` / ``{file}`` (the task's item). Other braces
  stay as they are.
- **Order.** With ``workers = 1`` (and no scheduler) the tasks run one after the other in this
  process, step by step, without Dask. Otherwise every task is a task of Dask distributed
  (:mod:`.batch_dask`) on a ``LocalCluster`` of ``workers`` processes (one thread each) or on
  the cluster of ``scheduler``; a task waits only for the tasks of earlier steps for the same
  model/image/file, for every task of an earlier step without items and for every task of an
  earlier step over another kind of item, so one model may be matched while another is still
  resampled. Every task calls :func:`.registry.run`, so its result is the same as from
  Python, the CLI or QGIS. Dask is optional: without it, a batch that needs it is refused in
  one line that says how to install it.
- **Lost workers.** A worker process that dies while running a task (killed, out of memory)
  costs only its own task: Dask runs it once more on another worker (logged: "its worker …
  was lost; running the task once more"); a second death makes it ``failed`` ("the worker
  running it died …, the second time for this task"). Each run of a task writes an
  ``attempt`` line to its log. A task that failed with an error is not run again. Other tasks
  and later steps go on as after any failure.
- **Parent death.** The local cluster's scheduler and nannies live in the batch process; its
  worker processes exit as soon as the batch process is gone. Their tasks' staged outputs are
  left as leftovers the next batch removes (see Leftovers).
- **Shared storage.** On a scheduler's cluster, the project and the run folder must be on
  storage that every worker sees at the same path; each worker is asked before the first task
  runs, and one that cannot see them stops the batch with one line naming it.
- **Lock.** ``<project>/.photodem/batch.lock`` (beside the resume state) is created atomically
  with the pid, host, start time and run folder of the batch; a second batch on the same
  project is refused at once with an operator error naming the holder. A lock whose process
  (on this host) is no longer running is taken over with a line in the batch log. The lock is
  removed on every exit of :func:`run_batch`; ``--dry-run`` does not take it.
- **Leftovers.** The batch's own files (state, lock, summary) are written atomically through
  staging names of :mod:`.output_policy`; at its start a batch removes those that ended
  processes left in ``.photodem`` and in its run folder, and names them in the batch log.
- **Checks first.** The batch file, every step's parameters (names, types, ranges, options),
  the lock and the run folder are checked before the first task runs; input files are not
  looked for then (an earlier step may make them).
- **Output policy while planning.** Every task's outputs (given or derived) are checked with
  :func:`.output_policy.check_targets`, as :func:`.registry.run` checks them again when the
  task runs: a forbidden output (a project, a project's ``images/`` or ``project.toml``, an
  input of the task, a file or folder another algorithm or the operator made, the run folder)
  stops the batch with one line naming the step and item before any task runs. Inputs an
  earlier step makes may be missing then; an output derived from a project an earlier step
  makes is left to the check at run time. The run folder is refused likewise when it is, holds
  or lies in a project part, is a file or holds an image of the project; it is written into,
  never replaced, so a named run folder may be reused.
- **Run folders** are unique: the default ``runs/<timestamp>/`` is created with an atomic
  ``mkdir``; if it exists already, ``<timestamp>-2`` (``-3`` …) is used and the tasks are
  planned again for it.
- **Failures.** A failed task does not stop the other tasks of its step. A later step's task for
  the same model/image is not run (status ``failed``, "not run because …"); other tasks go on.
  The batch status is ``failed`` and the CLI exits 1.
- **Resume.** After each finished task its parameter hash and outputs are recorded in
  ``<project>/.photodem/batch-state.json``. With ``resume`` (the default) a task is ``skipped``
  when the record has the same hash (same algorithm and same parameters after placeholder
  substitution) and every recorded file/folder output still exists. Outputs inside ``{run}``
  therefore never resume (each run has a new folder); put products under ``{project}``. Input
  file contents are not hashed.
- **Cancel.** :meth:`Feedback.cancel` (Ctrl-C in the CLI) stops scheduling; running tasks are
  asked to stop (a Dask event their Feedback checks), which makes the algorithms discard their
  staged outputs; a local cluster whose tasks do not stop within ``grace`` seconds is closed,
  which kills its workers (a scheduler's workers are left to finish them). The batch is
  ``cancelled`` only when a task was: a task that finished before the cancel reached it stays
  ``done``, and a cancel after the last task changes nothing.
- **Logs.** ``<run>/batch.log`` (the whole run), one log per task (``<run>/<step>.log`` or
  ``<run>/<step>/<item>.log``) and ``<run>/summary.json`` with each task's status
  (``done``/``skipped``/``failed``/``cancelled``), outputs, duration and error message.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import hashlib
import json
import os
import re
import socket
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, TextIO, Tuple, Union

from .. import output_policy
from ..errors import Cancelled, InputError, Message, PhotodemError, msg
from ..feedback import Feedback, ensure_feedback
from ..project import toml_io
from ..raster import tiled_dask
from . import registry
from .spec import Parameter, project_files, split_list

#: Environment variable with extra algorithm modules (comma-separated, importable names) that
#: the CLI and batch workers register in addition to the built-in ones (tests, site extensions).
STATE_FILE = Path(".photodem") / "batch-state.json"
#: The lock of a running batch, beside the resume state: one batch per project at a time.
LOCK_FILE = Path(".photodem") / "batch.lock"
SUMMARY_FILE = "summary.json"
TASK_STATUSES = ("done", "skipped", "failed", "cancelled")
_PLACEHOLDER = re.compile(r"\{(project|run|step|model|image|file)\}")
_BATCH_KEYS = {"project", "workers", "output", "scheduler"}
_STEP_KEYS = {"algorithm", "name", "models", "images", "files", "params"}
#: Parameter kinds whose values are files: a step over them iterates over ``files``.
_FILE_ITEM_KINDS = ("raster", "file")
#: What a step iterates over, one and many, as phrases of the messages (translated by the GUIs).
_ITEM = {"model": msg("model"), "image": msg("image"), "file": msg("file")}
_ITEMS = {"model": msg("models"), "image": msg("images"), "file": msg("files")}

PathLike = Union[str, "os.PathLike[str]"]


# -- the plan ------------------------------------------------------------------------------------
@dataclass
class Task:
    """One algorithm run of a batch."""

    index: int
    step: str
    algorithm: str
    item: Optional[str]  # the model or image name (or the file path) of an iterating step
    item_kind: Optional[str]  # "model", "image" or "file"
    params: Dict[str, Any]  # raw values, placeholders substituted
    log: Path

    @property
    def name(self) -> Optional[str]:
        """The item's name: a model or image name, or a file's name without suffix."""
        return _item_label(self.item, self.item_kind)

    @property
    def key(self) -> str:
        """Identity of the task across runs: ``step`` or ``step/item``."""
        return self.step if self.item is None else f"{self.step}/{self.name}"

    @property
    def params_hash(self) -> str:
        text = json.dumps({"algorithm": self.algorithm, "params": self.params},
                          sort_keys=True, default=str)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclass
class BatchPlan:
    """A parsed batch file: the project, the run folder, the steps and their tasks."""

    project: Optional[Path]  # None: a batch over files only
    run_dir: Path
    workers: int
    steps: List[str]
    #: The folder of the resume state (.photodem/batch-state.json): the project, or the
    #: batch file's folder for a batch over files.
    state_home: Path
    tasks: List[Task] = field(default_factory=list)
    file: Optional[Path] = None
    #: The parsed batch file and its folder: :func:`run_batch` plans again when the default
    #: run folder was taken meanwhile (another batch started in the same second).
    config: Optional[Dict[str, Any]] = field(default=None, repr=False)
    base_dir: Optional[Path] = field(default=None, repr=False)
    #: True when the run folder is the default ``runs/<timestamp>/`` (not named by the batch).
    run_auto: bool = False
    #: A Dask scheduler's address (``tcp://host:8786``); None: this machine.
    scheduler: Optional[str] = None

    def to_dict(self) -> Dict[str, Any]:
        return {
            "file": str(self.file) if self.file else None,
            "project": str(self.project) if self.project else None,
            "run": str(self.run_dir),
            "workers": self.workers,
            "scheduler": self.scheduler,
            "steps": list(self.steps),
            "tasks": [
                {"step": t.step, "algorithm": t.algorithm, "item": t.item, "params": t.params,
                 "log": str(t.log), "hash": t.params_hash}
                for t in self.tasks
            ],
        }


def load_batch(path: PathLike, run_dir: Optional[PathLike] = None,
               now: Optional[_dt.datetime] = None) -> BatchPlan:
    """Read a batch TOML file and plan its tasks.

    Relative paths in ``[batch]`` are relative to the batch file's folder.

    Raises
    ------
    InputError
        For an unreadable file, unknown keys, unknown algorithms, models or images.
    """
    file = Path(path)
    if not file.is_file():
        raise InputError.of("Batch file '{path}' does not exist.", path=file)
    try:
        config = toml_io.loads(file.read_text(encoding="utf-8"))
    except Exception as exc:  # tomllib.TOMLDecodeError
        raise InputError.of("Cannot read batch file '{path}': {error}", path=file,
                            error=exc) from exc  # the TOML parser's detail stays English
    plan = plan_batch(config, base_dir=file.resolve().parent, run_dir=run_dir, now=now)
    plan.file = file.resolve()
    return plan


def plan_batch(config: Dict[str, Any], base_dir: PathLike = ".",
               run_dir: Optional[PathLike] = None,
               now: Optional[_dt.datetime] = None) -> BatchPlan:
    """Plan the tasks of a batch given as a dict (the parsed TOML).

    Every task's parameters and outputs are checked here, before the first task runs.
    """
    from ..project.model import Project  # lazy: keeps photodem list fast (numpy and friends)

    unknown = set(config) - {"batch", "steps"}
    if unknown:
        raise InputError.of("Batch file: unknown table(s) {tables}; expected [batch] and "
                            "[[steps]].", tables=", ".join(sorted(unknown)))
    head = config.get("batch", {})
    if not isinstance(head, dict):
        raise InputError.of("Batch file: batch must be a table: write [batch] on a line of its "
                            "own with project = …, workers = …, output = … below it.")
    head = dict(head)
    _check_keys(head, _BATCH_KEYS, "[batch]")
    for key in ("project", "output", "scheduler"):
        _text(head, key, "[batch]")
    project: Any = None
    project_dir: Optional[Path] = None
    if "project" in head:
        project_dir = (Path(base_dir) / Path(head["project"]).expanduser()).resolve()
        project = Project.load(project_dir)
        project_dir = project.root.resolve()
    home = project_dir or Path(base_dir).resolve()
    workers = head.get("workers", 1)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError.of("Batch file: workers = {value} in [batch] must be a whole number "
                            "≥ 1.", value=repr(workers))
    run_auto = run_dir is None and not head.get("output")
    given = run_dir is not None
    if run_dir is None:
        if head.get("output"):
            text = _substitute(head["output"],
                               {"project": str(project_dir)} if project_dir else {},
                               "[batch] output", keep_others=True)
            run_dir = Path(base_dir) / Path(text).expanduser()
        else:
            run_dir = _timestamped(home / "runs", now)
    run = Path(run_dir).resolve()
    named = "[batch] output" if head.get("output") and not given else msg("the run folder")
    _check_run_folder(run, project_dir, named)

    steps = config.get("steps", [])
    if isinstance(steps, dict):
        raise InputError.of("Batch file: write each step as [[steps]] (two brackets), not "
                            "[steps].")
    if not isinstance(steps, list) or not steps:
        raise InputError.of("Batch file: no [[steps]]; add at least one step with algorithm = "
                            "\"id\".")
    plan = BatchPlan(project=project_dir, run_dir=run, workers=workers, steps=[],
                     state_home=home, config=config, base_dir=Path(base_dir),
                     run_auto=run_auto, scheduler=check_scheduler(head.get("scheduler")))
    for number, step in enumerate(steps, start=1):
        if not isinstance(step, dict):
            raise InputError.of("Batch file: step {number} is not a table.", number=number)
        _plan_step(plan, project, step, number, Path(base_dir))
    return plan


def check_scheduler(address: Optional[str]) -> Optional[str]:
    """A Dask scheduler's address as given (``tcp://host:8786``, ``host:8786``), ``None`` for
    this machine (empty, or ``local`` as for the tiled algorithms' ``--scheduler``).

    Raises
    ------
    InputError
        An address without a port, or with spaces (:func:`.tiled_dask.check_scheduler`).
    """
    text = tiled_dask.check_scheduler(address)
    return None if text in ("", "local") else text


def _text(table: Dict[str, Any], key: str, where: Union[str, Message]) -> None:
    """Refuse a value that is not a string (a number or list where a name or path belongs)."""
    if key in table and not isinstance(table[key], str):
        raise InputError.of("Batch file: {key} = {value} in {where} must be a string in "
                            "quotes, e.g. {key} = \"…\".", key=key, value=repr(table[key]),
                            where=where)


def _check_keys(table: Dict[str, Any], allowed: set, where: Union[str, Message]) -> None:
    unknown = set(table) - allowed
    if unknown:
        raise InputError.of("Batch file: unknown key(s) {keys} in {where}; allowed are "
                            "{allowed}.", keys=", ".join(sorted(unknown)), where=where,
                            allowed=", ".join(sorted(allowed)))


def _timestamped(parent: Path, now: Optional[_dt.datetime]) -> Path:
    stamp = (now or _dt.datetime.now()).strftime("%Y%m%d-%H%M%S")
    candidate, n = parent / stamp, 2
    while candidate.exists():
        candidate, n = parent / f"{stamp}-{n}", n + 1
    return candidate


def _plan_step(plan: BatchPlan, project: Any, step: Dict[str, Any], number: int,
               base_dir: Path) -> None:
    at = msg("step {number}", number=number)
    _check_keys(step, _STEP_KEYS, at)
    if "algorithm" not in step:
        raise InputError.of("Batch file: step {number} needs algorithm = \"id\".", number=number)
    for key in ("algorithm", "name"):
        _text(step, key, at)
    alg = registry.get(step["algorithm"])
    name = step.get("name") or alg.id
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise InputError.of("Batch file: step name {name} may hold only letters, digits, "
                            "'_', '-' and '.' (it names the log files).", name=repr(name))
    if name in plan.steps:
        raise InputError.of("Batch file: two steps are named {name}; give them distinct names.",
                            name=repr(name))
    plan.steps.append(name)
    params = step.get("params", {})
    if not isinstance(params, dict):
        raise InputError.of("Batch file: params of step '{step}' must be a table.", step=name)
    params = dict(params)
    for p in alg.parameters:  # the batch project unless the step names another one
        if p.is_project and p.name not in params:
            if project is None and p.required:
                raise InputError.of("Batch file: step '{step}' ({algorithm}) needs a project; "
                                    "set project = \"<project folder>\" in [batch].",
                                    step=name, algorithm=alg.id)
            if project is not None:
                params[p.name] = "{project}"

    iterate = alg.iterates_over
    item_kind: Optional[str] = None
    if iterate is not None:
        item_kind = _item_kind(alg.parameter(iterate))
        if item_kind is None:
            raise InputError(f"{alg.id}: iterates_over names '{iterate}', which is not a "
                             "model, image, raster or file parameter.")
    for key in ("models", "images", "files"):
        if key in step and (item_kind is None or key != item_kind + "s"):
            if item_kind is None:
                raise InputError.of("Batch file: step '{step}' sets {key}, but {algorithm} does "
                                    "not iterate.", step=name, key=key, algorithm=alg.id)
            raise InputError.of("Batch file: step '{step}' sets {key}, but {algorithm} iterates "
                                "over {items}.", step=name, key=key, algorithm=alg.id,
                                items=_ITEMS[item_kind])
    items: List[Optional[str]] = [None]
    if item_kind == "file" and iterate not in params:
        items = _step_files(step.get("files"), base_dir, name, iterate)  # type: ignore[arg-type]
    elif item_kind is not None and iterate not in params:
        if project is None:
            raise InputError.of("Batch file: step '{step}' runs over the project's {items}; set "
                                "project = \"<project folder>\" in [batch].", step=name,
                                items=_ITEMS[item_kind])
        available = ([m.name for m in project.models] if item_kind == "model"
                     else [i.name for i in project.images])
        chosen = step.get(item_kind + "s", "all")
        if chosen == "all":
            items = list(available)
        elif isinstance(chosen, list):
            missing = [c for c in chosen if str(c) not in available]
            if missing:
                raise InputError.of(
                    "Batch file: step '{step}': {kind}(s) {missing} not in the project; it has "
                    "{available}.", step=name, kind=_ITEM[item_kind],
                    missing=", ".join(map(str, missing)),
                    available=", ".join(available) or msg("none"))
            items = [str(c) for c in chosen]
        else:
            raise InputError.of("Batch file: step '{step}': {items} must be \"all\" or a list "
                                "of names.", step=name, items=_ITEMS[item_kind])
        if not items:
            raise InputError.of("Batch file: step '{step}': the project has no {items}.",
                                step=name, items=_ITEMS[item_kind])

    for item in items:
        values = {"run": str(plan.run_dir), "step": name}
        if plan.project is not None:
            values["project"] = str(plan.project)
        label = _item_label(item, item_kind)
        if label is not None:
            values[item_kind] = label  # type: ignore[index]
        task_params = {k: _anchored(alg, k, _substitute(v, values, name), base_dir)
                       for k, v in params.items()}
        if item is not None:
            task_params[iterate] = item  # type: ignore[index]
        values = _check_params(alg, task_params, name)
        where = (msg("step '{step}' ({algorithm})", step=name, algorithm=alg.id)
                 if label is None else
                 msg("step '{step}' ({algorithm}), {kind} '{label}'", step=name,
                     algorithm=alg.id, kind=_ITEM[item_kind], label=label))
        _check_task_outputs(alg, values, plan.run_dir, where)
        log = plan.run_dir / (f"{name}.log" if label is None else f"{name}/{_safe(label)}.log")
        plan.tasks.append(Task(index=len(plan.tasks), step=name, algorithm=alg.id, item=item,
                               item_kind=item_kind, params=task_params, log=log))


def _check_params(alg: Any, params: Dict[str, Any], step: str) -> Dict[str, Any]:
    """Refuse unknown names, missing required values and values of the wrong type or range
    while planning, so that a typo stops the batch before its first task runs.

    Input files are not looked for: an earlier step may make them.

    Returns
    -------
    dict
        The converted values (as :meth:`Parameter.convert` gives them to the run).
    """
    known = {p.name for p in alg.parameters}
    unknown = sorted(set(params) - known)
    if unknown:
        raise InputError.of("Batch file: step '{step}' ({algorithm}): unknown parameter(s) "
                            "{unknown}; known are {known}.", step=step, algorithm=alg.id,
                            unknown=", ".join(unknown), known=", ".join(sorted(known)))
    values = {}
    for p in alg.parameters:
        try:
            values[p.name] = p.convert(params.get(p.name))
        except InputError as exc:
            raise InputError.of("Batch file: step '{step}' ({algorithm}): {error}", step=step,
                                algorithm=alg.id, error=exc) from None
    return values


def _check_run_folder(run: Path, project: Optional[Path], named: Union[str, Message]
                      ) -> None:
    """Refuse a run folder the output policy forbids, before anything is written.

    The batch writes its logs and summary into the run folder but never replaces it, so a
    named run folder may be reused; everything else of :func:`.output_policy.check_targets`
    applies: no project folder, nothing that holds one, no project part (``images/``,
    ``.photodem/``, ``project.toml``, ``edits.gpkg``, an image), no file, no working folder.

    Parameters
    ----------
    run : Path
        The resolved run folder.
    project : Path, optional
        The batch project, whose files no run folder may be or contain.
    named : str or Message
        Where the run folder comes from, for the message (``[batch] output``, "the run
        folder").

    Raises
    ------
    InputError
        One line naming the run folder and what to do.
    """
    protected = project_files(project) if project is not None else []
    target = output_policy.Target(run, "folder", "output", reuse=True)
    try:
        output_policy.check_targets("batch", [target], protected=protected)
    except InputError as exc:
        raise InputError.of("Batch file: {named} (where the batch writes its logs): {error}",
                            named=named, error=exc) from None


def _check_task_outputs(alg: Any, values: Dict[str, Any], run: Path,
                        where: Union[str, Message]) -> None:
    """Check a task's outputs while planning (:func:`.registry.check_outputs` with the run
    folder): a forbidden output stops the batch before its first task.

    Parameters
    ----------
    alg : Algorithm
        The step's algorithm.
    values : dict
        The task's converted values (from :func:`_check_params`).
    run : Path
        The resolved run folder: no output may be or contain it.
    where : str or Message
        ``step 'name' (algorithm)[, model 'name']`` for the message.

    Raises
    ------
    InputError
        One line: ``where`` and the policy's message.
    """
    try:
        registry.check_outputs(alg, values, run_folder=run)
    except PhotodemError as exc:
        raise InputError.of("Batch file: {where}: {error}", where=where, error=exc) from None


def _item_kind(p: Parameter) -> Optional[str]:
    """What a step over parameter ``p`` iterates over: ``"model"``, ``"image"``, ``"file"``
    (a raster or file parameter), or ``None`` when ``p`` cannot be iterated over."""
    if p.is_item_name:
        return p.kind
    return "file" if p.kind in _FILE_ITEM_KINDS else None


def _item_label(item: Optional[str], kind: Optional[str]) -> Optional[str]:
    """A model or image name as it is; a file by its name without suffix ({file}, logs)."""
    return Path(item).stem if item is not None and kind == "file" else item


def _anchored(alg: Any, name: str, value: Any, base_dir: Path) -> Any:
    """A relative path of a path parameter, taken relative to the batch file's folder."""
    try:
        p = alg.parameter(name)
    except KeyError:  # an unknown parameter: the algorithm's own check reports it
        return value
    if not p.is_path:
        return value
    if p.is_list and isinstance(value, str):
        value = split_list(value)
    if isinstance(value, list):
        return [_anchored_path(v, base_dir) for v in value]
    return _anchored_path(value, base_dir)


def _anchored_path(value: Any, base_dir: Path) -> Any:
    if not isinstance(value, str) or not value or Path(value).expanduser().is_absolute():
        return value
    return str(base_dir.resolve() / Path(value).expanduser())


def _step_files(spec: Union[str, List[Any], None], base_dir: Path, step: str,
                parameter: str) -> List[str]:
    """The files of a step: glob patterns or paths relative to the batch file, sorted."""
    if spec is None:
        raise InputError.of("Batch file: step '{step}' needs files = [\"<pattern or path>\", "
                            "…] (the values of its parameter '{parameter}').", step=step,
                            parameter=parameter)
    patterns = [spec] if isinstance(spec, str) else spec
    if not isinstance(patterns, list) or not patterns:
        raise InputError.of("Batch file: step '{step}': files must be a pattern or a list of "
                            "patterns/paths.", step=step)
    found: List[Path] = []
    for pattern in patterns:
        text = str(Path(str(pattern)).expanduser())
        path = Path(text) if Path(text).is_absolute() else base_dir / text
        if any(c in text for c in "*?["):
            anchor = Path(path.anchor) if path.is_absolute() else Path(".")
            matches = sorted(p for p in anchor.glob(str(path.relative_to(anchor)))
                             if p.is_file())
            if not matches:
                raise InputError.of("Batch file: step '{step}': no file matches '{pattern}'.",
                                    step=step, pattern=pattern)
            found += matches
        elif path.is_file():
            found.append(path)
        else:
            raise InputError.of("Batch file: step '{step}': file '{pattern}' does not exist.",
                                step=step, pattern=pattern)
    files = list(dict.fromkeys(p.resolve() for p in found))  # once each, in order
    stems: Dict[str, Path] = {}
    for f in files:
        if f.stem in stems:
            raise InputError.of("Batch file: step '{step}': '{first}' and '{second}' have the "
                                "same name; {{file}} must name one file (rename one).",
                                step=step, first=stems[f.stem], second=f)
        stems[f.stem] = f
    return [str(f) for f in files]


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)


def _substitute(value: Any, values: Dict[str, str], step: str, keep_others: bool = False
                ) -> Any:
    if isinstance(value, list):
        return [_substitute(v, values, step, keep_others) for v in value]
    if not isinstance(value, str):
        return value

    def repl(match: re.Match) -> str:
        key = match.group(1)
        if key in values:
            return values[key]
        if keep_others:
            return match.group(0)
        if key == "project":
            raise InputError.of("Batch file: step '{step}' uses {{project}}, but the batch has "
                                "no project (set project = \"…\" in [batch]).", step=step)
        raise InputError.of("Batch file: step '{step}' uses {{{key}}}, but it does not run "
                            "per {key}.", step=step, key=key)

    return _PLACEHOLDER.sub(repl, value)


# -- resume state --------------------------------------------------------------------------------
def _state_path(project: Path) -> Path:
    return project / STATE_FILE


def read_state(project: Path) -> Dict[str, Any]:
    """The resume records of the tasks of earlier batches of ``project`` (by task key); empty
    when there are none or the state file is unreadable."""
    path = _state_path(project)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    tasks = data.get("tasks", {}) if isinstance(data, dict) else {}
    return tasks if isinstance(tasks, dict) else {}


def _write_state(project: Path, tasks: Dict[str, Any]) -> None:
    _atomic_json(_state_path(project), {"format_version": 1, "tasks": tasks})


def _output_paths(algorithm: str, outputs: Dict[str, Any]) -> List[str]:
    """The file/folder outputs of a result (by the algorithm's output kinds)."""
    try:
        alg = registry.get(algorithm)
    except PhotodemError:
        return []
    paths = []
    for out in alg.outputs:
        value = outputs.get(out.name)
        if out.is_path and isinstance(value, str) and value:
            paths.append(value)
    return paths


def resumable(task: Task, state: Dict[str, Any]) -> Optional[Dict[str, Any]]:
    """The recorded outputs when ``task`` is complete from an earlier run, else ``None``."""
    record = state.get(task.key)
    if not isinstance(record, dict) or record.get("hash") != task.params_hash:
        return None
    outputs = record.get("outputs", {})
    if not isinstance(outputs, dict):
        return None
    if all(Path(p).exists() for p in _output_paths(task.algorithm, outputs)):
        return outputs
    return None


# -- running one task (in this process or in a worker) ------------------------------------------
class _TaskFeedback(Feedback):
    """Writes a task's log file; cancellation and progress come from / go to the batch."""

    def __init__(self, log: TextIO, is_canceled: Callable[[], bool],
                 on_progress: Optional[Callable[[float], None]] = None) -> None:
        super().__init__(on_progress=on_progress)
        self._log = log
        self._is_canceled = is_canceled

    def is_canceled(self) -> bool:
        return self._cancel.is_set() or self._is_canceled()

    def _write(self, level: str, message: str) -> None:
        stamp = time.strftime("%H:%M:%S")
        self._log.write(f"{stamp} {level:7s} {message}\n")
        self._log.flush()

    def info(self, message: str) -> None:
        super().info(message)
        self._write("INFO", message)

    def warning(self, message: str) -> None:
        super().warning(message)
        self._write("WARNING", message)


def execute_task(algorithm: str, params: Dict[str, Any], log_path: PathLike,
                 is_canceled: Callable[[], bool],
                 on_progress: Optional[Callable[[float], None]] = None) -> Dict[str, Any]:
    """Run one task through :func:`.registry.run`, logging to ``log_path``.

    Returns ``{"status", "outputs", "duration_s", "error", "warnings"}`` and, for an operator
    error with a template, ``error_message`` (:meth:`~..errors.Message.to_dict`); never raises
    for errors of the algorithm (they become status ``failed``; cancellation ``cancelled``).
    """
    log_path = Path(log_path)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    with open(log_path, "a", encoding="utf-8") as log:
        feedback = _TaskFeedback(log, is_canceled, on_progress)
        feedback._write("INFO", f"{algorithm} {json.dumps(params, default=str)}")
        result: Dict[str, Any] = {"status": "done", "outputs": {}, "error": None}
        try:
            result["outputs"] = registry.run(algorithm, params, feedback)
        except Cancelled as exc:
            result.update(status="cancelled", error=str(exc))
        except PhotodemError as exc:
            result.update(status="failed", error=str(exc))
            if exc.message is not None:  # the GUIs show it in the operator's language
                result["error_message"] = exc.message.to_dict()
        except Exception as exc:  # a bug: keep the traceback in the task log
            result.update(status="failed", error=f"{type(exc).__name__}: {exc}")
            log.write(traceback.format_exc())
        if result["error"]:
            feedback._write("ERROR" if result["status"] == "failed" else "INFO", result["error"])
        result["duration_s"] = round(time.perf_counter() - start, 3)
        result["warnings"] = list(feedback.warnings)
    return result


def no_result(status: str, error: str) -> Dict[str, Any]:
    """The record of a task that ended without running to its end (not run, lost, cancelled)."""
    return {"status": status, "outputs": {}, "duration_s": 0.0, "error": error}


# -- the batch -----------------------------------------------------------------------------------
class _Progress:
    """Overall progress = mean of the task fractions; forwarded without raising Cancelled."""

    def __init__(self, feedback: Feedback, n: int) -> None:
        self.feedback = feedback
        self.fraction = [0.0] * n

    def set(self, index: int, pct: float) -> None:
        # never backwards: a worker's last queued report may arrive after its task finished
        self.fraction[index] = max(self.fraction[index], min(max(pct / 100.0, 0.0), 1.0))
        total = 100.0 * sum(self.fraction) / max(len(self.fraction), 1)
        with contextlib.suppress(Cancelled):  # the batch loop checks is_canceled() itself
            self.feedback.progress(total)
        _notify(self.feedback, "task_progress", index, 100.0 * self.fraction[index])


def _notify(feedback: Feedback, hook: str, *args: Any) -> None:
    """Call an optional per-task hook of the feedback (``task_progress(index, pct)``: a task
    started (0) or progressed; ``task_finished(index, record)``), e.g. for the batch dialog."""
    method = getattr(feedback, hook, None)
    if callable(method):
        method(*args)


def run_batch(
    plan: BatchPlan,
    feedback: Optional[Feedback] = None,
    workers: Optional[int] = None,
    resume: bool = True,
    extra_modules: Sequence[str] = (),
    grace: float = 10.0,
    scheduler: Optional[str] = None,
) -> Dict[str, Any]:
    """Run a planned batch and return its summary (also written to ``<run>/summary.json``).

    Parameters
    ----------
    plan : BatchPlan
        From :func:`load_batch`. A default (timestamped) run folder that exists already is
        replaced by a new one (``…-2``), and the tasks' ``{run}`` values with it.
    feedback : Feedback, optional
        Receives the overall progress (share of tasks finished, including the running tasks'
        own progress), one log line per task, and cancellation. Optional per-task hooks of
        the feedback are called in the batch's thread: ``task_progress(index, pct)`` (0 when a
        task starts) and ``task_finished(index, record)`` (the batch dialog's rows).
    workers : int, optional
        Worker processes of a local Dask cluster; default ``plan.workers``. ``1`` runs the
        tasks in this process (without Dask).
    resume : bool
        Skip tasks that an earlier run completed with the same parameters.
    extra_modules : sequence of str
        Modules with extra ``ALGORITHMS`` to register in the workers (besides those named in
        :data:`.registry.EXTRA_MODULES_ENV`, which workers inherit).
    grace : float
        Seconds that running tasks get to stop after a cancel before their workers are
        killed.
    scheduler : str, optional
        A Dask scheduler's address (``tcp://host:8786``); default ``plan.scheduler``. Its
        workers run the tasks (``workers`` is then not used); they must see the project and
        the run folder at the same paths.

    Returns
    -------
    dict
        ``status`` (``done``, ``failed`` or ``cancelled``), ``counts`` per task status, the
        ``run`` folder, ``summary`` path and ``tasks`` (step, algorithm, item, status, outputs,
        duration_s, error, log).

    Raises
    ------
    InputError
        When another batch holds the lock of the project (or of the resume state's folder),
        the run folder cannot be created, Dask is needed but not installed, the scheduler is
        not reachable or a worker cannot see the project or the run folder.
    """
    feedback = ensure_feedback(feedback)
    scheduler = check_scheduler(scheduler if scheduler is not None else plan.scheduler)
    if scheduler or (workers if workers is not None else plan.workers) > 1:
        from .batch_dask import import_distributed  # lazy: Dask only when it is needed

        import_distributed()  # before the lock and the run folder: nothing to undo
    n_workers = max(1, int(workers if workers is not None else plan.workers))
    lock, notes = _acquire_lock(plan)
    try:
        run_dir = plan.run_dir
        _claim_run_dir(plan)
        if plan.run_dir != run_dir:
            notes.append(f"run folder {run_dir} exists already; this run writes to "
                         f"{plan.run_dir}")
            _atomic_json(lock, _lock_info(plan))
        output_policy.remove_stale([lock.parent, plan.run_dir], notes.append)
        modules = [*extra_modules, *registry.extra_modules()]
        return _run_locked(plan, feedback, n_workers, resume, modules, grace, notes,
                           scheduler)
    finally:
        _release_lock(lock)


class _Hooks:
    """What the batch does as tasks start and finish: ``batch.log``, the records, the resume
    state and the progress (in the batch's thread)."""

    def __init__(self, plan: BatchPlan, feedback: Feedback, batch_log: TextIO) -> None:
        self.plan = plan
        self.feedback = feedback
        self.batch_log = batch_log
        self.progress = _Progress(feedback, len(plan.tasks))
        self.records: List[Dict[str, Any]] = [
            {"step": t.step, "algorithm": t.algorithm, "item": t.item, "status": "cancelled",
             "outputs": {}, "duration_s": 0.0, "error": None, "log": str(t.log),
             "hash": t.params_hash}
            for t in plan.tasks
        ]

    def log(self, message: str, warning: bool = False, quiet: bool = False) -> None:
        """A line in batch.log and (unless ``quiet``) for the operator."""
        self.batch_log.write(f"{time.strftime('%H:%M:%S')} {message}\n")
        self.batch_log.flush()
        if not quiet:
            (self.feedback.warning if warning else self.feedback.info)(message)

    def finish(self, task: Task, result: Dict[str, Any]) -> None:
        """Record a task's result (and, when done, its resume record)."""
        record = self.records[task.index]
        record.update({k: result.get(k) for k in ("status", "outputs", "duration_s", "error")})
        if result.get("warnings"):
            record["warnings"] = result["warnings"]
        if result.get("error_message"):
            record["error_message"] = result["error_message"]
        if record["status"] != "cancelled":
            self.progress.set(task.index, 100.0)
        _notify(self.feedback, "task_finished", task.index, dict(record))
        label = task.key
        if record["status"] == "done":
            home = self.plan.state_home
            state_all = read_state(home)
            state_all[task.key] = {"hash": task.params_hash, "algorithm": task.algorithm,
                                   "outputs": record["outputs"], "run": str(self.plan.run_dir),
                                   "finished": _dt.datetime.now().isoformat(timespec="seconds")}
            _write_state(home, state_all)
            self.log(f"{label}: done in {record['duration_s']:.1f} s")
        elif record["status"] == "skipped":
            self.log(f"{label}: skipped (complete from an earlier run)")
        elif record["status"] == "failed":
            self.log(f"{label}: FAILED: {record['error']}", warning=True)
        elif record["status"] == "cancelled":
            self.log(f"{label}: cancelled")


def _run_locked(plan: BatchPlan, feedback: Feedback, n_workers: int, resume: bool,
                modules: Sequence[str], grace: float, notes: List[str],
                scheduler: Optional[str]) -> Dict[str, Any]:
    """The body of :func:`run_batch`, with the lock held and the run folder created."""
    started = _dt.datetime.now().isoformat(timespec="seconds")
    t0 = time.perf_counter()
    state = read_state(plan.state_home) if resume else {}
    batch_log = open(plan.run_dir / "batch.log", "a", encoding="utf-8")  # noqa: SIM115
    hooks = _Hooks(plan, feedback, batch_log)
    where = (f"Dask scheduler {scheduler}" if scheduler
             else "this process" if n_workers == 1 else f"{n_workers} worker(s)")
    hooks.log(f"batch {plan.file or ''}: {len(plan.tasks)} task(s) in {len(plan.steps)} "
              f"step(s), {where}, run folder {plan.run_dir}")
    for note in notes:
        hooks.log(note)
    try:
        if n_workers == 1 and not scheduler:
            _run_in_process(plan, hooks, state if resume else None)
        else:
            n_workers = _run_on_dask(plan, hooks, state if resume else None, n_workers,
                                     scheduler, modules, grace)
    finally:
        summary = _summary(plan, hooks.records, started, t0, n_workers, resume)
        if scheduler:
            summary["scheduler"] = scheduler
        _atomic_json(plan.run_dir / SUMMARY_FILE, summary)
        batch_log.write(f"{time.strftime('%H:%M:%S')} batch {summary['status']}: "
                        + ", ".join(f"{v} {k}" for k, v in summary["counts"].items() if v)
                        + "\n")
        batch_log.close()
    return summary


def _run_in_process(plan: BatchPlan, hooks: _Hooks, state: Optional[Dict[str, Any]]) -> None:
    """Run the tasks one after the other in this process (``workers = 1``, no Dask)."""
    failed_items: Dict[tuple, str] = {}
    feedback = hooks.feedback
    for task in plan.tasks:
        if feedback.is_canceled():
            return  # the records of the tasks not started say "cancelled"
        blocker = failed_items.get((task.item_kind, task.item))
        if task.item is not None and blocker is not None:
            hooks.finish(task, no_result("failed", f"not run because step '{blocker}' failed "
                                                   f"for {task.item_kind} '{task.name}'"))
        else:
            outputs = resumable(task, state) if state is not None else None
            if outputs is not None:
                hooks.finish(task, {"status": "skipped", "outputs": outputs,
                                    "duration_s": 0.0, "error": None})
                continue
            hooks.progress.set(task.index, 0.0)  # started (per-task hooks show it as running)
            result = execute_task(task.algorithm, task.params, task.log, feedback.is_canceled,
                                  lambda pct, i=task.index: hooks.progress.set(i, pct))
            hooks.finish(task, result)
        if hooks.records[task.index]["status"] == "failed" and task.item is not None:
            failed_items.setdefault((task.item_kind, task.item), task.step)


def _run_on_dask(plan: BatchPlan, hooks: _Hooks, state: Optional[Dict[str, Any]],
                 n_workers: int, scheduler: Optional[str], modules: Sequence[str],
                 grace: float) -> int:
    """Run the tasks on Dask (a LocalCluster of ``n_workers``, or ``scheduler``'s cluster).

    Returns
    -------
    int
        The number of workers that ran the batch.
    """
    from . import batch_dask  # lazy: Dask only for workers > 1 or a scheduler

    skip: Dict[int, Dict[str, Any]] = {}
    for task in plan.tasks:
        outputs = resumable(task, state) if state is not None else None
        if outputs is not None:
            skip[task.index] = outputs
    with batch_dask.connect(n_workers, scheduler) as (client, cluster):
        link = batch_dask.dashboard(client, local=cluster is not None)
        hooks.log(f"Dask dashboard: {link or 'none'}", quiet=link is None)
        folders = [("the run folder", plan.run_dir)]
        if plan.project is not None:
            folders.insert(0, ("the project folder", plan.project))
        n_workers = batch_dask.check_shared_paths(client, folders)
        run = batch_dask.DaskRun(client, hooks, modules)
        depends = batch_dask.dependencies(plan.tasks)
        futures = run.submit(plan.tasks, skip, depends)
        killed = run.follow(plan.tasks, futures, hooks.feedback, float(grace),
                            can_kill=cluster is not None)
        if killed and cluster is not None:
            hooks.log("closing the local Dask cluster: tasks did not stop after the cancel",
                      quiet=True)
    return n_workers


def _summary(plan: BatchPlan, records: List[Dict[str, Any]], started: str, t0: float,
             n_workers: int, resume: bool) -> Dict[str, Any]:
    """The batch summary; its status comes from the tasks' records only, so a cancel that
    came after every task had finished does not make the batch ``cancelled``."""
    counts = {s: sum(r["status"] == s for r in records) for s in TASK_STATUSES}
    if counts["cancelled"]:
        status = "cancelled"
    elif counts["failed"]:
        status = "failed"
    else:
        status = "done"
    return {
        "file": str(plan.file) if plan.file else None,
        "project": str(plan.project) if plan.project else None,
        "run": str(plan.run_dir),
        "status": status,
        "started": started,
        "duration_s": round(time.perf_counter() - t0, 3),
        "workers": n_workers,
        "resume": resume,
        "counts": counts,
        "summary": str(plan.run_dir / SUMMARY_FILE),
        "tasks": records,
    }


def _atomic_json(path: Path, data: Dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)  # the summary even if a task removed it
    tmp = path.with_name(output_policy.staging_name(path.name))
    tmp.write_text(json.dumps(data, indent=2, default=str), encoding="utf-8")
    os.replace(tmp, path)


# -- the run folder ------------------------------------------------------------------------------
_STAMP = re.compile(r"(\d{8}-\d{6})(?:-(\d+))?")


def _claim_run_dir(plan: BatchPlan) -> None:
    """Create the run folder; a default one that exists already becomes ``<stamp>-N``.

    ``mkdir`` without ``exist_ok`` is atomic: two batches started in the same second get
    different folders. A run folder the batch file names (``output``) may be reused.
    """
    try:
        if not plan.run_auto or plan.config is None:
            plan.run_dir.mkdir(parents=True, exist_ok=True)
            return
        while True:
            try:
                plan.run_dir.mkdir(parents=True, exist_ok=False)
                return
            except FileExistsError:
                _replan(plan, _next_run_dir(plan.run_dir))
    except OSError as exc:
        raise InputError(f"Cannot create the run folder '{plan.run_dir}': "
                         f"{exc.strerror or exc}; set output = \"…\" in [batch] to a "
                         "writable folder.") from exc


def _next_run_dir(run: Path) -> Path:
    match = _STAMP.fullmatch(run.name)
    if match is None:
        return run.with_name(f"{run.name}-2")
    return run.with_name(f"{match.group(1)}-{int(match.group(2) or 1) + 1}")


def _replan(plan: BatchPlan, run: Path) -> None:
    """Plan the tasks again for another run folder (``{run}`` and the logs move with it)."""
    fresh = plan_batch(plan.config or {}, plan.base_dir or ".", run_dir=run)
    plan.run_dir, plan.tasks = fresh.run_dir, fresh.tasks


# -- the lock ------------------------------------------------------------------------------------
#: Seconds after which an unreadable lock file (its writer died while creating it) is stale.
_LOCK_UNREADABLE_STALE_S = 30.0


def _lock_path(plan: BatchPlan) -> Path:
    return plan.state_home / LOCK_FILE


def _lock_info(plan: BatchPlan) -> Dict[str, Any]:
    pid = os.getpid()
    return {"pid": pid, "host": socket.gethostname(),
            "pid_start": output_policy.process_start(pid),
            "started": _dt.datetime.now().isoformat(timespec="seconds"),
            "run": str(plan.run_dir)}


def _acquire_lock(plan: BatchPlan) -> Tuple[Path, List[str]]:
    """Take ``<state home>/.photodem/batch.lock`` (atomically); a stale one is taken over.

    Returns the lock's path and notes for the batch log.

    Raises
    ------
    InputError
        When a running batch holds the lock (naming its pid, start and run folder), or the
        lock cannot be written.
    """
    path = _lock_path(plan)
    notes: List[str] = []
    try:
        for _ in range(5):
            path.parent.mkdir(parents=True, exist_ok=True)  # again: a releaser may remove it
            if _create_lock(path, _lock_info(plan)):
                return path, notes
            holder = _read_lock(path)
            for _wait in range(10):  # a lock created without a hard link is written just after
                if holder != {}:
                    break
                time.sleep(0.05)
                holder = _read_lock(path)
            if holder is None:
                continue  # released just now
            if not _lock_is_stale(path, holder):
                raise InputError(_held_message(plan, path, holder))
            if _remove_stale_lock(path, holder):
                notes.append(f"took over the stale lock {path} of batch pid "
                             f"{holder.get('pid', '?')} (started "
                             f"{holder.get('started', '?')}), which is no longer running")
    except OSError as exc:
        raise InputError(f"Cannot write the batch lock '{path}': {exc.strerror or exc}; check "
                         "that the folder is writable.") from exc
    raise InputError(f"Cannot take the batch lock '{path}': other batches keep taking it; "
                     "try again.")


def _create_lock(path: Path, info: Dict[str, Any]) -> bool:
    """Create the lock file with its content in one atomic step; False if it exists.

    The content is written to a private file first and hard-linked to the lock's name (which
    fails when it exists, like ``O_CREAT|O_EXCL``), so no other batch ever reads a half-written
    lock. Where hard links are not supported, the lock is created with ``O_CREAT|O_EXCL``.
    """
    tmp = path.with_name(output_policy.staging_name(path.name))
    try:
        tmp.write_text(json.dumps(info), encoding="utf-8")
        os.link(tmp, path)
        return True
    except (FileExistsError, FileNotFoundError):  # taken, or the folder went: look again
        return False
    except OSError:  # no hard links on this file system
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            return False
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(info, f)
        return True
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _read_lock(path: Path) -> Optional[Dict[str, Any]]:
    """The lock's holder; ``{}`` when unreadable, ``None`` when the lock is gone."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _lock_is_stale(path: Path, holder: Dict[str, Any]) -> bool:
    """A lock whose process (on this host) is dead, or that stayed unreadable for long."""
    if not holder:
        with contextlib.suppress(OSError):
            return time.time() - path.stat().st_mtime > _LOCK_UNREADABLE_STALE_S
        return False
    if holder.get("host") != socket.gethostname():
        return False  # cannot tell from here
    pid = holder.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return True
    return not output_policy.pid_alive(pid, holder.get("pid_start"))


def _held_message(plan: BatchPlan, path: Path, holder: Dict[str, Any]) -> str:
    where = ("this project" if plan.project is not None
             else f"the batch files of '{plan.state_home}'")
    if not holder:
        who = "another batch (its lock is being written)"
    else:
        host = holder.get("host")
        on = "" if host == socket.gethostname() else f" on host {host}"
        who = (f"another batch (pid {holder.get('pid', '?')}{on}, started "
               f"{holder.get('started', '?')}, run folder {holder.get('run', '?')})")
    return (f"{who} is running on {where}; wait for it to finish or stop it (if no batch is "
            f"running, delete '{path}').")


def _remove_stale_lock(path: Path, holder: Dict[str, Any]) -> bool:
    """Delete the stale lock unless another batch took it over meanwhile."""
    with _exclusive(path.parent):  # one takeover at a time: check and delete are one step
        if _read_lock(path) != holder:
            return False
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
    return True


@contextlib.contextmanager
def _exclusive(folder: Path) -> Iterator[None]:
    """Hold an advisory lock on ``folder`` itself (POSIX ``flock``, no extra file; elsewhere
    no guard)."""
    try:  # a platform check, not a cycle: fcntl is POSIX only
        import fcntl
    except ImportError:  # Windows
        yield
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the flock


def _release_lock(path: Path) -> None:
    """Delete the lock if it is still ours, and its folder if that is empty now (a batch
    that could not start leaves nothing behind)."""
    holder = _read_lock(path)
    if holder and holder.get("pid") == os.getpid() and holder.get("host") == socket.gethostname():
        with contextlib.suppress(OSError):
            path.unlink()
        with contextlib.suppress(OSError):  # not empty: the resume state lives there
            path.parent.rmdir()


def batch_template(project: PathLike) -> str:
    """An example batch file for ``project`` (``photodem batch --template PROJECT``).

    The example steps use algorithms of the registry: for each, the required parameters are
    filled in (outputs below ``{project}/products/{step}/…``) and the optional ones are listed
    as comments with their defaults.
    """
    lines = [
        "# PhotoDEM batch file: run with  photodem batch THIS_FILE.toml",
        "# Placeholders in parameter values: {project} {run} {step} {model} {image} {file}",
        "",
        "[batch]",
        f"project = {_toml_string(str(project))}",
        "workers = 2",
        "# output = \"{project}/runs/my-run\"   # default: <project>/runs/<timestamp>/",
        "",
    ]
    algs = registry.algorithms()
    chosen = [a for a in ("project_info", "epipolar_pair") if a in algs]
    if not chosen:
        chosen = [a.id for a in algs.values() if a.iterates_over][:1] or list(algs)[:1]
    for alg_id in chosen:
        alg = algs[alg_id]
        lines += ["[[steps]]", f"algorithm = {_toml_string(alg.id)}   # {alg.name}",
                  f"name = {_toml_string(alg.id)}"]
        if alg.iterates_over:
            kind = alg.parameter(alg.iterates_over).kind
            lines.append(f"{kind}s = \"all\"   # or a list: [\"name1\", \"name2\"]")
        lines.append("[steps.params]")
        for p in alg.parameters:
            if p.is_project or p.name == alg.iterates_over:
                continue
            if p.is_output:
                value = "{project}/products/{step}"
                if alg.iterates_over:
                    value += "/{" + alg.parameter(alg.iterates_over).kind + "}"
                if not p.is_folder:
                    value += "/" + p.name + (p.extensions[0] if p.extensions else "")
                lines.append(f"{p.name} = {_toml_string(value)}")
            elif p.required:
                lines.append(f"{p.name} = \"\"   # required: {p.description}")
            else:
                default = "" if p.default is None else f" (default {p.default!r})"
                lines.append(f"# {p.name} = …   # {p.description}{default}")
        lines.append("")
    if not chosen:
        lines += ["[[steps]]", "algorithm = \"project_info\"", ""]
    return "\n".join(lines)


def _toml_string(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)  # a JSON string is a valid TOML basic string


__all__ = [
    "BatchPlan",
    "Task",
    "batch_template",
    "execute_task",
    "load_batch",
    "plan_batch",
    "read_state",
    "resumable",
    "run_batch",
]
