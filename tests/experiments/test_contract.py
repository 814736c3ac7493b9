"""The experiment contract and the one generic ``reproduce``, on a tiny in-process experiment."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pytest

import navtrack
from navtrack.cli import main
from navtrack.experiments import (
    HEADER_FIELDS,
    Experiment,
    ExperimentContext,
    ExtraResult,
    MissingDataError,
    Outcome,
    ReproduceOptions,
    reproduce,
    shared_data_dir,
)
from navtrack.experiments.contract import EXTRA_SPAWN_KEY
from navtrack.experiments.parameters import (
    ParameterError,
    apply_parameters,
    parameter_fields,
    parse_assignments,
    read_parameter_file,
)
from navtrack.experiments.runner import run_generator


@dataclass(frozen=True, slots=True)
class ToyParams:
    """Parameters of the toy experiment (no paper: test values)."""

    n: int = 3
    scale: float = 1.0
    mode: Literal["sum", "max"] = "sum"
    offsets: tuple[float, ...] = (0.0,)
    flag: bool = False
    path: Path | None = None
    cases: tuple[ToyCase, ...] = ()

    def __post_init__(self) -> None:
        if self.n < 1:
            raise ValueError(f"n: expected >= 1, got {self.n}")


@dataclass(frozen=True, slots=True)
class ToyCase:
    name: str


class ToyExperiment(Experiment[ToyParams, float]):
    name = "toy"
    description = "a test experiment: sums of normal draws"
    params_type = ToyParams
    default_runs = 2

    def run_one(self, params: ToyParams, rng: np.random.Generator) -> float:
        draws = params.scale * rng.normal(size=params.n) + sum(params.offsets)
        return float(draws.sum() if params.mode == "sum" else draws.max())

    def summarize(self, params: ToyParams, runs: Sequence[float]) -> dict[str, Any]:
        return {"values": list(runs), "mean": float(np.mean(runs)) if runs else None}

    def extra(self, params: ToyParams, context: ExperimentContext) -> ExtraResult:
        draw = float(context.rng.normal())
        return ExtraResult({"extra_draw": draw, "inputs": list(context.inputs)}, artifacts=draw)

    def tables(self, results: dict[str, Any]) -> str:
        return f"# toy\n\nruns {results['runs']}, mean {results['mean']}\n"

    def figures(self, outcome: Outcome[ToyParams, float], out_dir: Path) -> list[Path]:
        path = out_dir / "toy.txt"
        path.write_text(f"{len(outcome.runs)} {outcome.artifacts}\n")
        return [path]

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return [f"mean {results['mean']}"]


TOY = ToyExperiment()


def _options(out: Path, **kw: Any) -> ReproduceOptions:
    kw.setdefault("backend", "loop")
    return ReproduceOptions(out_dir=out, progress=False, **kw)


def test_results_json_header(tmp_path: Path) -> None:
    params = ToyParams(n=4, path=Path("x.csv"))
    results = reproduce(TOY, _options(tmp_path, runs=3, seed=7, params=params))
    data = json.loads((tmp_path / "results.json").read_text())
    assert list(data)[: len(HEADER_FIELDS)] == list(HEADER_FIELDS)
    assert data["experiment"] == "toy"
    assert data["description"] == TOY.description
    assert data["parameters"] == {
        "n": 4,
        "scale": 1.0,
        "mode": "sum",
        "offsets": [0.0],
        "flag": False,
        "path": "x.csv",
        "cases": [],
    }
    assert data["seed"] == 7
    assert data["runs"] == 3
    assert data["package_version"] == navtrack.__version__
    assert data["git_revision"] is None or len(data["git_revision"]) == 40
    assert data["backend"] == "loop"
    assert data["wall_time_s"] > 0
    assert data["run_counts"] == {"ok": 3, "error": 0, "resumed": 0}
    assert data["run_errors"] == []
    # then the summary, the extra step, the figures
    assert len(data["values"]) == 3
    assert data["mean"] == pytest.approx(np.mean(data["values"]))
    assert data["figures"] == [str(tmp_path / "toy.txt")]
    assert (tmp_path / "toy.txt").read_text() == f"3 {results['extra_draw']}\n"
    assert (tmp_path / "tables.md").read_text() == f"# toy\n\nruns 3, mean {data['mean']}\n"


def test_stages_are_logged_and_each_figure_as_it_is_written(tmp_path: Path) -> None:
    class TwoFigures(ToyExperiment):
        def figures(self, outcome: Outcome[ToyParams, float], out_dir: Path) -> Iterator[Path]:
            for name in ("a.txt", "b.txt"):
                # the line of the figure before must be out before the next one is written
                assert lines[-1].startswith("figure" if name == "b.txt" else "extra")
                (out_dir / name).write_text(name)
                yield out_dir / name

    lines: list[str] = []
    results = reproduce(TwoFigures(), _options(tmp_path, runs=1, log=lines.append))
    assert lines[0].startswith("extra      real data")
    assert lines[1].startswith("extra      done in ")
    assert lines[2:] == [f"figure     {tmp_path / 'a.txt'}", f"figure     {tmp_path / 'b.txt'}"]
    assert results["figures"] == [str(tmp_path / "a.txt"), str(tmp_path / "b.txt")]


def test_context_progress_bar_goes_to_stderr_only_when_asked(
    capsys: pytest.CaptureFixture[str],
) -> None:
    rng = np.random.default_rng(0)
    quiet = ExperimentContext(0, rng, progress=False)
    assert list(quiet.track([1, 2, 3], "cases")) == [1, 2, 3]
    assert capsys.readouterr().err == ""
    shown = ExperimentContext(0, rng, progress=True)
    assert list(shown.track([1, 2, 3], "cases")) == [1, 2, 3]
    assert "cases" in capsys.readouterr().err


def test_runs_use_their_spawned_generators(tmp_path: Path) -> None:
    params = ToyParams(n=2, scale=3.0)
    results = reproduce(TOY, _options(tmp_path, runs=4, seed=5, params=params))
    expected = [TOY.run_one(params, run_generator(5, i)) for i in range(4)]
    assert results["values"] == expected
    extra_rng = np.random.default_rng(np.random.SeedSequence(5, spawn_key=(EXTRA_SPAWN_KEY,)))
    assert results["extra_draw"] == float(extra_rng.normal())


def test_same_seed_same_numbers_other_seed_others(tmp_path: Path) -> None:
    a = reproduce(TOY, _options(tmp_path / "a", runs=3, seed=1))
    b = reproduce(TOY, _options(tmp_path / "b", runs=3, seed=1))
    c = reproduce(TOY, _options(tmp_path / "c", runs=3, seed=2))
    assert a["values"] == b["values"]
    assert a["extra_draw"] == b["extra_draw"]
    assert a["values"] != c["values"]


def test_dask_threads_give_the_loop_numbers(tmp_path: Path) -> None:
    pytest.importorskip("dask")
    loop = reproduce(TOY, _options(tmp_path / "loop", runs=5, seed=3))
    threads = reproduce(TOY, _options(tmp_path / "dask", runs=5, seed=3, backend="auto"))
    assert threads["backend"] == "dask-threads"
    assert threads["values"] == loop["values"]


def test_resume_skips_finished_runs(tmp_path: Path) -> None:
    first = reproduce(TOY, _options(tmp_path, runs=3, seed=9))
    again = reproduce(TOY, _options(tmp_path, runs=3, seed=9))
    assert again["run_counts"] == {"ok": 3, "error": 0, "resumed": 3}
    assert again["values"] == first["values"]
    (tmp_path / "runs" / "run_000001.pkl").unlink()
    partly = reproduce(TOY, _options(tmp_path, runs=4, seed=9))
    assert partly["run_counts"]["resumed"] == 2
    assert partly["values"][:3] == first["values"]
    # other parameters do not mix with the checkpoints of these
    with pytest.raises(ValueError, match="refusing to mix"):
        reproduce(TOY, _options(tmp_path, runs=3, seed=9, params=ToyParams(n=5)))


def test_params_of_another_type_are_refused(tmp_path: Path) -> None:
    with pytest.raises(TypeError, match="expected ToyParams"):
        reproduce(TOY, _options(tmp_path, params={"n": 3}))


def test_unknown_experiment_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"unknown experiment 'nope'; known: (.*, )?ari"):
        reproduce("nope", ReproduceOptions(out_dir=tmp_path))


def test_set_values_are_typed_by_the_fields() -> None:
    values = parse_assignments(
        ["n=5", "scale=2.5", "mode=max", "offsets=1, 2.5", "flag=yes", "path=/tmp/t.csv", "n=6"]
    )
    params = apply_parameters(ToyParams(), values, experiment="toy")
    assert params == ToyParams(6, 2.5, "max", (1.0, 2.5), True, Path("/tmp/t.csv"))
    assert apply_parameters(params, {"path": "none", "offsets": ""}).path is None
    assert apply_parameters(params, {"offsets": ""}).offsets == ()
    assert apply_parameters(params, {"flag": "off"}).flag is False


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("n", "five", r"parameter 'n': expected int, got 'five'"),
        ("scale", "x", r"parameter 'scale': expected float"),
        ("mode", "min", r"'min' is not one of \{'sum', 'max'\}"),
        ("flag", "maybe", r"parameter 'flag': expected bool"),
        ("offsets", "1,a", r"parameter 'offsets': expected float, got 'a'"),
        ("n", "0", r"n: expected >= 1, got 0"),  # the dataclass' own check
        ("cases", "a", r"parameter 'cases' \(tuple\[ToyCase, ...\]\) cannot be set"),
    ],
)
def test_bad_values_are_refused_by_name(key: str, value: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        apply_parameters(ToyParams(), {key: value}, experiment="toy", source="--set")


def test_unknown_key_is_refused_by_name() -> None:
    with pytest.raises(
        ParameterError,
        match=r"--set: unknown parameter 'size' of experiment 'toy'; known: n, scale, mode, "
        r"offsets, flag, path, cases",
    ):
        apply_parameters(
            ToyParams(), parse_assignments(["size=3"]), experiment="toy", source="--set"
        )
    with pytest.raises(ParameterError, match="key=value"):
        parse_assignments(["n"])


def test_toml_parameters(tmp_path: Path) -> None:
    path = tmp_path / "toy.toml"
    path.write_text('n = 7\nscale = 2\noffsets = [1, 2.5]\nmode = "max"\nflag = true\n')
    params = apply_parameters(ToyParams(), read_parameter_file(path), experiment="toy")
    assert params == ToyParams(7, 2.0, "max", (1.0, 2.5), True)
    assert isinstance(params.scale, float)
    path.write_text("flag = 1\n")  # TOML integers are not booleans
    with pytest.raises(ParameterError, match=r"parameter 'flag': expected bool, got 1"):
        apply_parameters(ToyParams(), read_parameter_file(path))
    path.write_text("n = [\n")
    with pytest.raises(ValueError, match="not a TOML file"):
        read_parameter_file(path)


def test_parameter_fields_list_types_and_defaults() -> None:
    fields = {f.name: f for f in parameter_fields(ToyParams)}
    assert fields["offsets"].type_name == "tuple[float, ...]"
    assert fields["mode"].type_name == "{'sum', 'max'}"
    assert fields["path"].type_name == "Path | None"
    assert fields["n"].default == 3
    assert not fields["cases"].settable
    assert all(f.settable for name, f in fields.items() if name != "cases")


def test_cli_list_prints_experiments_and_parameters(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["reproduce", "--list"]) == 0
    out = capsys.readouterr().out.splitlines()
    start = next(i for i, line in enumerate(out) if line.startswith("ari: "))  # sorted by name
    assert out[start].startswith("ari: Paper 5: ARI(p,d) filtering")
    assert "(default runs 20)" in out[start]
    rows: dict[str, list[str]] = {}
    for line in out[start + 1 :]:
        if not line.startswith("  "):  # the next experiment
            break
        rows[line.split()[0]] = line.split()
    assert rows["outlier_rate"] == ["outlier_rate", "float", "default", "0.01"]
    assert rows["outlier_sigma"] == [
        "outlier_sigma",
        "tuple[float,",
        "float]",
        "default",
        "5.0,15.0",
    ]
    assert rows["select_order"][-1] == "true"
    assert rows["cases"][-2:] == ["(not", "settable)"]


def test_cli_refuses_unknown_key_before_running(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match=r"unknown parameter 'nope' of experiment 'ari'; known: "):
        main(["reproduce", "ari", "--out", str(tmp_path), "--set", "nope=1"])
    path = tmp_path / "p.toml"
    path.write_text('robust = "l1"\n')
    with pytest.raises(SystemExit, match=r"p.toml: parameter 'robust': 'l1' is not one of"):
        main(["reproduce", "ari", "--out", str(tmp_path), "--params", str(path)])
    assert not (tmp_path / "results.json").exists()


def test_shared_data_missing_names_both_places(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("NAVTRACK_SHARED_DATA", str(tmp_path / "absent"))
    assert shared_data_dir() == tmp_path / "absent"  # not required: the caller skips data sets
    with pytest.raises(MissingDataError, match=r"NAVTRACK_SHARED_DATA=.*absent.*shared/data"):
        shared_data_dir(required=True)
    monkeypatch.setenv("NAVTRACK_SHARED_DATA", str(tmp_path))
    assert shared_data_dir(required=True) == tmp_path
    context = ExperimentContext(0, np.random.default_rng(0))
    assert context.shared_data(required=True) == tmp_path


def test_default_params_are_the_dataclass_defaults() -> None:
    assert TOY.default_params() == ToyParams()
    assert dataclasses.is_dataclass(TOY.params_type)
