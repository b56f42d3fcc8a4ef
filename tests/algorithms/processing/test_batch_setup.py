"""The batch dialog's core: step states of earlier runs, batch files from choices (Qt-free)."""

from __future__ import annotations

import datetime as dt

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import batch, batch_setup
from photodem.algorithms.processing.batch_setup import BatchChoices
from photodem.algorithms.project import toml_io


def test_choices_become_a_batch_file_the_runner_plans(project_dir):
    choices = BatchChoices(project_dir, ["a_b", "c_d"], list(batch_setup.STEP_ORDER),
                           workers=3, method="dense", match_preset="urban",
                           filter="filter_linear_prediction", filter_preset="forest",
                           ortho="orthorectify")
    path = batch_setup.write_batch(choices)
    assert path.parent == project_dir.resolve() / ".photodem" / "batches"
    assert path.name.startswith("batch-") and path.suffix == ".toml"
    assert "photodem batch" in path.read_text()  # says how to run it again
    config = toml_io.loads(path.read_text())
    assert [s["algorithm"] for s in config["steps"]] == [
        "epipolar_pair", "match_model", "dsm_merge", "refine_object_space",
        "filter_linear_prediction", "orthorectify"]
    match = config["steps"][1]
    assert match["models"] == ["a_b", "c_d"]
    assert match["params"]["method"] == "dense" and match["params"]["preset"] == "urban"
    assert config["steps"][2]["params"]["inputs"] == [
        "{project}/products/dsm/a_b/dsm.tif", "{project}/products/dsm/c_d/dsm.tif"]
    assert config["steps"][5]["images"] == ["a", "b", "c", "d"]
    plan = batch.load_batch(path)
    assert plan.workers == 3 and plan.project == project_dir.resolve()
    assert [t.key for t in plan.tasks][:2] == ["epipolar_pair/a_b", "epipolar_pair/c_d"]
    assert plan.tasks[-1].params["dem"] == str(
        project_dir.resolve() / "products/dtm/filter_linear_prediction/dtm.tif")
    assert "scheduler" not in config["batch"] and plan.scheduler is None  # this machine


def test_a_scheduler_goes_into_the_batch_file(project_dir):
    choices = BatchChoices(project_dir, ["a_b"], ["epipolar_pair"],
                           scheduler=" tcp://10.0.0.5:8786 ")
    config = batch_setup.batch_config(choices)
    assert config["batch"]["scheduler"] == "tcp://10.0.0.5:8786"
    assert batch.load_batch(batch_setup.write_batch(choices)).scheduler == "tcp://10.0.0.5:8786"
    choices.scheduler = "10.0.0.5"  # no port
    with pytest.raises(InputError, match="tcp://host:port"):
        batch_setup.batch_config(choices)


def test_bad_choices_are_refused_with_a_reason(project_dir):
    with pytest.raises(InputError, match="model"):
        batch_setup.batch_config(BatchChoices(project_dir, [], ["match_model"]))
    with pytest.raises(InputError, match="step"):
        batch_setup.batch_config(BatchChoices(project_dir, ["a_b"], []))
    with pytest.raises(InputError, match="dsm_merge"):  # two DSMs, nothing merges them
        batch_setup.batch_config(BatchChoices(project_dir, ["a_b", "b_c"],
                                              ["match_model", "filter"]))
    one = batch_setup.batch_config(BatchChoices(project_dir, ["a_b"], ["match_model", "filter"]))
    assert one["steps"][1]["params"]["input"] == "{project}/products/dsm/a_b/dsm.tif"


def test_batch_paths_are_unique(project_dir):
    now = dt.datetime(2026, 1, 2, 3, 4, 5)
    first = batch_setup.new_batch_path(project_dir, now)
    first.parent.mkdir(parents=True)
    first.write_text("")
    assert batch_setup.new_batch_path(project_dir, now).name == "batch-20260102-030405-2.toml"


def test_step_states_come_from_the_state_and_the_summaries(fake_algs, project_dir):
    def run(models, fail, run_name):
        config = {"batch": {"project": str(project_dir), "workers": 1,
                            "output": f"{{project}}/runs/{run_name}"},
                  "steps": [{"algorithm": "fake_fail_on", "models": models,
                             "params": {"fail": fail,
                                        "output": "{project}/products/{step}/{model}.txt"}}]}
        return batch.run_batch(batch.plan_batch(config, base_dir=project_dir))

    summary = run(["a_b", "b_c"], "b_c", "r1")
    assert batch_setup.failed_items(summary) == ["b_c"]
    states = batch_setup.step_states(project_dir, ["a_b", "b_c", "c_d"], ["fake_fail_on"])
    assert states == {("fake_fail_on", "a_b"): "done", ("fake_fail_on", "b_c"): "failed"}
    (project_dir / "products" / "fake_fail_on" / "a_b.txt").unlink()  # a lost product
    run(["b_c"], "", "r2")  # the failed model alone, now fixed
    states = batch_setup.step_states(project_dir, ["a_b", "b_c", "c_d"], ["fake_fail_on"])
    assert states == {("fake_fail_on", "b_c"): "done"}
    rows = batch_setup.model_rows(project_dir)
    assert [r.name for r in rows] == ["a_b", "b_c", "c_d"]
    assert rows[0].states == {"epipolar_pair": "not run", "match_model": "not run"}


def test_only_items_keeps_the_failed_items_and_the_steps_without_items(project_dir):
    choices = BatchChoices(project_dir, ["a_b", "b_c", "c_d"],
                           ["epipolar_pair", "match_model", "dsm_merge"])
    plan = batch.load_batch(batch_setup.write_batch(choices))
    kept = batch_setup.only_items(plan.tasks, ["b_c"])
    assert [t.key for t in kept] == ["epipolar_pair/b_c", "match_model/b_c", "dsm_merge"]
    assert [t.index for t in kept] == [0, 1, 2]
    assert [t.key for t in batch_setup.only_items(plan.tasks, ["zz"])] == ["dsm_merge"]


def test_time_helpers():
    assert batch_setup.remaining_seconds(10.0, 0.01) is None
    assert batch_setup.remaining_seconds(10.0, 0.25) == pytest.approx(30.0)
    assert batch_setup.format_seconds(None) == "–"
    assert batch_setup.format_seconds(309) == "5:09"
    assert batch_setup.format_seconds(3909) == "1:05:09"
    assert batch_setup.default_workers() >= 1
