"""Monte Carlo runner: seeding, Dask back ends, checkpoint/resume, error capture, replay."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from navtrack.errors import CheckpointMismatchError
from navtrack.experiments import runner
from navtrack.experiments.runner import replay_run, run_generator, run_monte_carlo


def toy_run(index: int, rng: np.random.Generator, params: dict) -> dict:
    """A run that uses its generator, and fails on request."""
    if index in params.get("fail", ()):
        raise RuntimeError(f"run {index} failed on purpose")
    draws = rng.normal(size=params.get("size", 3))
    return {"index": index, "sum": float(draws.sum()), "first": float(draws[0])}


def _results(mc) -> list:
    return [r.result for r in mc.records]


def test_run_generator_is_the_spawned_child() -> None:
    children = np.random.SeedSequence(42).spawn(5)
    for i, child in enumerate(children):
        expected = np.random.default_rng(child).normal(size=4)
        np.testing.assert_array_equal(run_generator(42, i).normal(size=4), expected)
    with pytest.raises(ValueError, match="index"):
        run_generator(42, -1)


def test_loop_and_dask_threads_give_identical_results() -> None:
    pytest.importorskip("dask")
    params = {"size": 4}
    loop = run_monte_carlo(toy_run, 7, 123, params, backend="loop", progress=False)
    threads = run_monte_carlo(toy_run, 7, 123, params, progress=False)
    assert loop.backend == "loop"
    assert threads.backend == "dask-threads"
    assert _results(loop) == _results(threads)
    assert loop.n_ok == 7


def test_two_worker_processes_and_a_cluster_give_identical_results() -> None:
    pytest.importorskip("distributed")
    cloudpickle = pytest.importorskip("cloudpickle")
    # Workers cannot import this test module by name: ship toy_run by value.
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    from distributed import LocalCluster

    try:
        params = {"size": 2}
        loop = run_monte_carlo(toy_run, 5, 9, params, backend="loop", progress=False)
        processes = run_monte_carlo(toy_run, 5, 9, params, workers=2, progress=False)
        # an existing cluster, reached by its scheduler address
        with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as lc:
            remote = run_monte_carlo(
                toy_run, 5, 9, params, scheduler=lc.scheduler_address, progress=False
            )
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert processes.backend == "dask-processes"
    assert remote.backend == "dask-scheduler"
    assert _results(processes) == _results(loop)
    assert _results(remote) == _results(loop)


def test_without_dask_falls_back_to_loop_and_says_so(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runner, "dask_available", lambda: False)
    mc = run_monte_carlo(toy_run, 4, 5, {}, progress=False)
    assert mc.backend == "loop"
    assert "not installed" in mc.note
    reference = run_monte_carlo(toy_run, 4, 5, {}, backend="loop", progress=False)
    assert _results(mc) == _results(reference)


def test_resume_after_partial_run_matches_uninterrupted(tmp_path: Path) -> None:
    params = {"size": 3}
    full = run_monte_carlo(toy_run, 6, 77, params, backend="loop", progress=False)
    # "interrupted" after 3 runs, then resumed with all 6
    part = run_monte_carlo(
        toy_run, 3, 77, params, checkpoint_dir=tmp_path, backend="loop", progress=False
    )
    assert part.n_ok == 3
    assert len(list((tmp_path / "runs").glob("run_*.pkl"))) == 3
    resumed = run_monte_carlo(
        toy_run, 6, 77, params, checkpoint_dir=tmp_path, backend="loop", progress=False
    )
    assert resumed.n_resumed == 3
    assert [r.resumed for r in resumed.records] == [True] * 3 + [False] * 3
    assert _results(resumed) == _results(full)
    # a torn checkpoint file is recomputed, not trusted
    (tmp_path / "runs" / "run_000001.pkl").write_bytes(b"\x80")
    again = run_monte_carlo(
        toy_run, 6, 77, params, checkpoint_dir=tmp_path, backend="loop", progress=False
    )
    assert again.n_resumed == 5
    assert _results(again) == _results(full)


def test_checkpoints_of_another_experiment_are_refused(tmp_path: Path) -> None:
    run_monte_carlo(
        toy_run, 2, 1, {"size": 3}, checkpoint_dir=tmp_path, backend="loop", progress=False
    )
    # a user's input error (an output directory reused), which the CLI reports with exit 2
    with pytest.raises(CheckpointMismatchError, match="refusing to mix"):
        run_monte_carlo(
            toy_run, 2, 2, {"size": 3}, checkpoint_dir=tmp_path, backend="loop", progress=False
        )


def test_errors_are_captured_per_run(tmp_path: Path) -> None:
    params = {"fail": (2,), "size": 3}
    mc = run_monte_carlo(toy_run, 5, 3, params, checkpoint_dir=tmp_path, progress=False)
    ok, error = runner.RunStatus.OK, runner.RunStatus.ERROR
    assert [r.status for r in mc.records] == [ok, ok, error, ok, ok]
    assert "failed on purpose" in mc.records[2].error
    assert mc.counts == {"ok": 4, "error": 1, "resumed": 0}
    assert len(mc.results) == 4
    # errors are retried on resume; the successful runs are not recomputed
    rerun = run_monte_carlo(toy_run, 5, 3, params, checkpoint_dir=tmp_path, progress=False)
    assert rerun.n_resumed == 4
    assert rerun.n_error == 1


def test_replay_one_run_alone() -> None:
    mc = run_monte_carlo(toy_run, 8, 2024, {"size": 5}, backend="loop", progress=False)
    assert replay_run(toy_run, 2024, 6, {"size": 5}) == mc.records[6].result
    assert replay_run(toy_run, 2024, 6, {"size": 5}) != mc.records[5].result


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="n_runs"):
        run_monte_carlo(toy_run, -1, 0, {}, progress=False)
    with pytest.raises(ValueError, match="workers"):
        run_monte_carlo(toy_run, 1, 0, {}, workers=0, progress=False)
    with pytest.raises(ValueError, match="at most one"):
        run_monte_carlo(toy_run, 1, 0, {}, workers=2, scheduler="tcp://x:1", progress=False)
