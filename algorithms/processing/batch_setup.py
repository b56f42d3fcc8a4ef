"""What the batch dialog shows and writes: the state of earlier runs and a batch file from choices.

Qt-free, so the standalone tool, QGIS and the tests share it:

- :func:`model_rows` — the project's stereo models with the state of each per-model step from
  earlier batches (``done`` from the resume state when its outputs still exist, ``failed`` from
  the newest run summary that ran it, else ``not run``);
- :class:`BatchChoices` → :func:`batch_config` → :func:`write_batch`: the batch TOML the dialog
  runs, written to ``<project>/.photodem/batches/batch-<timestamp>.toml`` so that the same batch
  can be run again with ``photodem batch FILE``;
- :func:`summary_products`, :func:`failed_items`, :func:`remaining_seconds` for the run view.

The step chain (products below ``<project>/products/``, as the algorithms' defaults name them)::

    epipolar_pair  → products/epipolar/<model>/          (per model)
    match_model    → products/dsm/<model>/dsm.tif        (per model; method, preset)
    dsm_merge      → products/dsm_merged/dsm.tif         (the chosen models' DSMs)
    refine_object_space → products/dsm_refined/<source>/  (the merged or the one DSM)
    filter_*       → products/dtm/<filter>/dtm.tif      (the newest DSM; preset)
    orthorectify   → products/ortho/<image>.tif          (per image of the models; on the DTM)
    mosaic         → products/mosaic/mosaic.tif          (on the DTM)
"""

from __future__ import annotations

import datetime as _dt
import json
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from ..errors import InputError
from ..matching.presets import DEFAULT_PRESET
from ..project import toml_io
from . import registry
from .batch import SUMMARY_FILE, check_scheduler, read_state

#: Per-model steps, in the order of the chain.
MODEL_STEPS = ("epipolar_pair", "match_model")
#: The DTM filters the dialog offers (one of them per batch).
FILTERS = ("filter_lowpass", "filter_linear_prediction")
#: Orthophoto steps (one of them per batch).
ORTHO_STEPS = ("orthorectify", "mosaic")
#: Every step the dialog offers, in chain order (a filter / ortho step stands for its choice).
STEP_ORDER = ("epipolar_pair", "match_model", "dsm_merge", "refine_object_space", "filter",
              "ortho")
#: Where the dialog writes its batch files, inside the project.
BATCH_FOLDER = Path(".photodem") / "batches"
STATES = ("done", "failed", "not run")


# -- the models and their states -----------------------------------------------------------------
@dataclass
class ModelRow:
    """One stereo model of the table: its figures and the state of each per-model step."""

    name: str
    kind: str
    b_h: float
    overlap: float
    states: Dict[str, str] = field(default_factory=dict)  # step algorithm → done/failed/not run


def model_rows(project: Any) -> List[ModelRow]:
    """The stereo models of ``project`` (a Project or its folder) with their step states."""
    from ..project.model import Project  # lazy: numpy and friends only when a dialog opens

    if not isinstance(project, Project):
        project = Project.load(project)
    states = step_states(project.root, [m.name for m in project.models])
    return [ModelRow(m.name, m.kind, float(m.b_h), float(m.overlap),
                     {s: states.get((s, m.name), "not run") for s in MODEL_STEPS})
            for m in project.models]


def step_states(home: Path, items: Sequence[str],
                algorithms: Sequence[str] = MODEL_STEPS) -> Dict[Tuple[str, str], str]:
    """``(algorithm, item) → "done" | "failed"`` from earlier batches of ``home``.

    ``done``: the resume state holds a record whose outputs still exist (whatever the step was
    named). ``failed``: the newest run summary that ran the task says so and no record is
    done. Pairs not in the result were not run.
    """
    wanted = set(items)
    result: Dict[Tuple[str, str], str] = {}
    for summary in _summaries(Path(home)):  # oldest first: newer runs overwrite
        for task in summary.get("tasks", []):
            if not isinstance(task, dict):
                continue
            key = (str(task.get("algorithm")), str(task.get("item")))
            if key[1] in wanted and key[0] in algorithms and task.get("status") == "failed":
                result[key] = "failed"
            elif key in result and task.get("status") in ("done", "skipped"):
                del result[key]
    for key, record in read_state(Path(home)).items():
        if not isinstance(record, dict) or "/" not in key:
            continue
        item = key.split("/", 1)[1]
        algorithm = str(record.get("algorithm"))
        if item in wanted and algorithm in algorithms and _outputs_exist(record):
            result[(algorithm, item)] = "done"
    return result


def _summaries(home: Path) -> List[Dict[str, Any]]:
    """The summaries of the runs below ``home/runs``, oldest first (by folder name)."""
    runs = home / "runs"
    found = []
    if runs.is_dir():
        for folder in sorted(p for p in runs.iterdir() if p.is_dir()):
            try:
                data = json.loads((folder / SUMMARY_FILE).read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue
            if isinstance(data, dict):
                found.append(data)
    return found


def _outputs_exist(record: Dict[str, Any]) -> bool:
    outputs = record.get("outputs")
    if not isinstance(outputs, dict):
        return False
    paths = [v for v in outputs.values() if isinstance(v, str) and os.sep in v]
    return all(Path(p).exists() for p in paths)


# -- choices → batch file ------------------------------------------------------------------------
@dataclass
class BatchChoices:
    """What the operator chose in the dialog.

    ``steps`` holds entries of :data:`STEP_ORDER`; ``filter`` and ``ortho`` name the algorithm
    the ``"filter"`` / ``"ortho"`` step runs.
    """

    project: Path
    models: List[str]
    steps: List[str]
    workers: int = 1
    method: str = "fbm_lsm"
    match_preset: str = DEFAULT_PRESET
    filter: str = FILTERS[0]
    filter_preset: str = "auto"
    ortho: str = "mosaic"
    #: A Dask scheduler's address (``tcp://host:8786``); empty or None: this machine.
    scheduler: Optional[str] = None


def choice_options(algorithm: str, parameter: str) -> Tuple[str, ...]:
    """The options of an enum parameter, from the algorithm's spec (for the dialog's combos)."""
    return tuple(registry.get(algorithm).parameter(parameter).options)


def choice_default(algorithm: str, parameter: str) -> Any:
    """The default of a parameter, from the algorithm's spec."""
    return registry.get(algorithm).parameter(parameter).default



def default_workers() -> int:
    """Cores − 1 (at least 1): one core stays for the operator."""
    return max(1, (os.cpu_count() or 2) - 1)


def batch_config(choices: BatchChoices) -> Dict[str, Any]:
    """The batch file (as a dict) for ``choices``; paths use ``{project}`` placeholders.

    Raises
    ------
    InputError
        No model or no step chosen, a step that needs a DSM no chosen step makes, or a
        scheduler address that is not ``tcp://host:port``.
    """
    if not choices.models:
        raise InputError("Choose at least one stereo model.")
    chosen = [s for s in STEP_ORDER if s in choices.steps]
    if not chosen:
        raise InputError("Choose at least one step.")
    models = list(choices.models)
    steps: List[Dict[str, Any]] = []
    dsms = [f"{{project}}/products/dsm/{m}/dsm.tif" for m in models]
    dsm: Optional[str] = dsms[0] if len(dsms) == 1 else None
    if "epipolar_pair" in chosen:
        steps.append(_model_step("epipolar_pair", models,
                                 {"output": "{project}/products/epipolar/{model}"}))
    if "match_model" in chosen:
        steps.append(_model_step("match_model", models, {
            "method": choices.method, "preset": choices.match_preset,
            "output": "{project}/products/dsm/{model}"}))
    if "dsm_merge" in chosen:
        steps.append({"algorithm": "dsm_merge", "params": {
            "inputs": dsms, "output": "{project}/products/dsm_merged/dsm.tif"}})
        dsm = "{project}/products/dsm_merged/dsm.tif"
    if "refine_object_space" in chosen:
        source = _need_dsm(dsm, "refine_object_space")
        name = "merged" if "dsm_merge" in chosen else models[0]
        steps.append({"algorithm": "refine_object_space", "params": {
            "dsm": source, "output": f"{{project}}/products/dsm_refined/{name}"}})
        dsm = f"{{project}}/products/dsm_refined/{name}/dsm.tif"
    dtm: Optional[str] = None
    if "filter" in chosen:
        source = _need_dsm(dsm, choices.filter)
        steps.append({"algorithm": choices.filter, "params": {
            "input": source, "preset": choices.filter_preset,
            "output": f"{{project}}/products/dtm/{choices.filter}"}})
        dtm = f"{{project}}/products/dtm/{choices.filter}/dtm.tif"
    if "ortho" in chosen:
        steps.append(_ortho_step(choices, dtm or dsm))
    head: Dict[str, Any] = {"project": str(Path(choices.project).resolve()),
                            "workers": int(choices.workers)}
    scheduler = check_scheduler(choices.scheduler)
    if scheduler:
        head["scheduler"] = scheduler
    return {"batch": head, "steps": steps}


def _model_step(algorithm: str, models: List[str], params: Dict[str, Any]) -> Dict[str, Any]:
    return {"algorithm": algorithm, "models": list(models), "params": params}


def _need_dsm(dsm: Optional[str], step: str) -> str:
    if dsm is None:
        raise InputError(f"{step} needs one DSM: choose dsm_merge as well, or a single model.")
    return dsm


def _ortho_step(choices: BatchChoices, dem: Optional[str]) -> Dict[str, Any]:
    """orthorectify (per image of the chosen models) or mosaic, on the DTM (else the DSM)."""
    if dem is None:
        raise InputError(f"{choices.ortho} needs a DEM: choose a filter, dsm_merge or a single "
                         "model with match_model.")
    if choices.ortho == "orthorectify":
        from ..project.model import Project  # lazy: numpy and friends

        project = Project.load(choices.project)
        images: List[str] = []
        for m in project.models:
            if m.name in choices.models:
                images += [i for i in (m.left, m.right) if i not in images]
        return {"algorithm": "orthorectify", "images": images,
                "params": {"dem": dem, "output": "{project}/products/ortho/{image}.tif"}}
    return {"algorithm": "mosaic", "params": {
        "dem": dem, "output": "{project}/products/mosaic/mosaic.tif"}}


def batch_text(config: Dict[str, Any]) -> str:
    """The TOML text of a batch config, with a header that says how to run it again."""
    head = ("# PhotoDEM batch file (written by the batch dialog); run it again with\n"
            "#   photodem batch THIS_FILE.toml\n")
    return head + toml_io.dumps(config)


def new_batch_path(project: Path, now: Optional[_dt.datetime] = None) -> Path:
    """``<project>/.photodem/batches/batch-<timestamp>.toml`` (``-2``, ``-3`` … if taken)."""
    stamp = (now or _dt.datetime.now()).strftime("%Y%m%d-%H%M%S")
    folder = Path(project).resolve() / BATCH_FOLDER
    path = folder / f"batch-{stamp}.toml"
    number = 2
    while path.exists():
        path = folder / f"batch-{stamp}-{number}.toml"
        number += 1
    return path


def write_batch(choices: BatchChoices, path: Optional[Path] = None) -> Path:
    """Write the batch file of ``choices`` (default :func:`new_batch_path`) and return it.

    Only the project's own ``.photodem/batches/`` folder is written unless ``path`` is given.
    """
    config = batch_config(choices)
    path = Path(path) if path is not None else new_batch_path(choices.project)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(batch_text(config), encoding="utf-8")
    os.replace(tmp, path)
    return path


def only_items(tasks: Sequence[Any], items: Sequence[str]) -> List[Any]:
    """The tasks of a plan for the models/images/files named in ``items`` (by name), and the
    steps without items (merge, filter, mosaic), which depend on them; renumbered so that the
    runner's records match (``Task.index``). Resume then skips whatever is complete.

    Parameters
    ----------
    tasks : sequence of Task
        ``BatchPlan.tasks`` of the batch file to run again.
    items : sequence of str
        Task names (a model or image name, a file name without suffix), e.g. the failed ones.
    """
    wanted = set(items)
    kept = [t for t in tasks if t.item is None or t.name in wanted]
    return [replace(t, index=i) for i, t in enumerate(kept)]


# -- after a run ---------------------------------------------------------------------------------
#: Output kinds that are products to open or add to a map.
_PRODUCT_KINDS = ("raster", "vector")
#: Algorithms whose outputs are intermediate (epipolar images are not georeferenced): not
#: listed as products nor added to a map.
_INTERMEDIATE = ("epipolar_pair",)


def summary_products(summary: Dict[str, Any]) -> List[str]:
    """The raster and vector products of the done/skipped tasks of a batch summary, once each,
    in task order (existing files only; not the epipolar images, which are intermediate)."""
    products: List[str] = []
    for task in summary.get("tasks", []):
        if task.get("status") not in ("done", "skipped") or task.get("algorithm") in _INTERMEDIATE:
            continue
        try:
            alg = registry.get(task["algorithm"])
        except Exception:  # an algorithm no longer registered: nothing to show
            continue
        outputs = task.get("outputs") or {}
        for out in alg.outputs:
            value = outputs.get(out.name)
            if out.kind in _PRODUCT_KINDS and isinstance(value, str) and Path(value).is_file() \
                    and value not in products:
                products.append(value)
    return products


def failed_items(summary: Dict[str, Any]) -> List[str]:
    """The models/images (file names) whose tasks failed, once each, in task order."""
    items: List[str] = []
    for task in summary.get("tasks", []):
        item = task.get("item")
        if task.get("status") == "failed" and item is not None:
            name = Path(str(item)).stem if os.sep in str(item) else str(item)
            if name not in items:
                items.append(name)
    return items


def remaining_seconds(elapsed: float, fraction: float) -> Optional[float]:
    """Remaining time from the elapsed time and the share done (``None`` until 2 % are done)."""
    if fraction < 0.02 or elapsed <= 0:
        return None
    return max(0.0, elapsed * (1.0 - fraction) / fraction)


def format_seconds(seconds: Optional[float]) -> str:
    """``1:05:09`` / ``5:09`` / ``–`` for unknown."""
    if seconds is None:
        return "–"
    hours, rest = divmod(round(seconds), 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


__all__ = [
    "BATCH_FOLDER",
    "FILTERS",
    "MODEL_STEPS",
    "ORTHO_STEPS",
    "STEP_ORDER",
    "BatchChoices",
    "ModelRow",
    "batch_config",
    "batch_text",
    "choice_default",
    "choice_options",
    "default_workers",
    "failed_items",
    "format_seconds",
    "model_rows",
    "new_batch_path",
    "only_items",
    "remaining_seconds",
    "step_states",
    "summary_products",
    "write_batch",
]
