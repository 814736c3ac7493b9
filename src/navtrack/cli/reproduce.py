"""``navtrack reproduce NAME --out DIR``: rerun a seed paper's experiment.

Everything experiment-specific comes through the typed contract
(:class:`navtrack.experiments.Experiment`): the parameters are its ``params_type`` fields, typed
and checked by :mod:`navtrack.experiments.parameters`; the console summary is the common header
(:func:`navtrack.experiments.header_lines`) plus its ``summary_lines``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from navtrack.experiments import (
    EXPERIMENTS,
    ReproduceOptions,
    get_experiment,
    header_lines,
    reproduce,
)
from navtrack.experiments.parameters import (
    ParameterError,
    apply_parameters,
    parameter_fields,
    parse_assignments,
    read_parameter_file,
)


def register(subparsers: Any) -> None:
    cmd = subparsers.add_parser(
        "reproduce",
        help="reproduce a seed paper's experiment (tables, figures, results.json)",
        description="Run a registered reproduction: seeded Monte Carlo runs (resumable, through "
        "Dask when installed), then DIR/results.json, DIR/tables.md and PNG figures. "
        f"Experiments: {', '.join(sorted(EXPERIMENTS))} (--list shows their parameters).",
    )
    cmd.add_argument("name", nargs="?", help="experiment name", choices=sorted(EXPERIMENTS))
    cmd.add_argument(
        "--list", action="store_true", help="list the experiments with their parameters"
    )
    cmd.add_argument("--out", type=Path, help="output directory (required to run)")
    cmd.add_argument("--runs", type=int, help="Monte Carlo runs (default: the experiment's)")
    cmd.add_argument("--seed", type=int, default=0, help="root seed (default 0)")
    cmd.add_argument(
        "--workers", type=int, help="run on N local worker processes (Dask multiprocessing)"
    )
    cmd.add_argument("--scheduler", help="address of an existing Dask scheduler (tcp://...)")
    cmd.add_argument(
        "--set",
        dest="assignments",
        metavar="KEY=VALUE",
        action="append",
        default=[],
        help="set a parameter (typed by the experiment; tuples comma-separated); repeatable, "
        "applied after --params",
    )
    cmd.add_argument("--params", type=Path, metavar="FILE.toml", help="parameters from a TOML file")
    cmd.add_argument(
        "--input",
        type=Path,
        action="append",
        default=[],
        help="extra input file the experiment understands (ari: solution tables); repeatable",
    )
    cmd.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    cmd.add_argument("--no-progress", action="store_true", help="no progress bar")
    cmd.set_defaults(func=run_reproduce)


def list_lines() -> list[str]:
    """Every registered experiment: name, description, and its parameters (name, type, default)."""
    lines: list[str] = []
    for name in sorted(EXPERIMENTS):
        exp = get_experiment(name)
        lines.append(f"{name}: {exp.description} (default runs {exp.default_runs})")
        fields = parameter_fields(exp.params_type)
        width = max((len(f.name) for f in fields), default=0)
        type_width = max((len(f.type_name) for f in fields), default=0)
        for f in fields:
            lines.append(
                f"  {f.name:<{width}}  {f.type_name:<{type_width}}  default {_show(f.default)}"
                + ("" if f.settable else "  (not settable)")
            )
    return lines


def _show(value: Any) -> str:
    """A default value as the command line would take it (tuples comma-separated)."""
    if isinstance(value, tuple):
        if all(isinstance(v, bool | int | float | str | Path) for v in value):
            return ",".join(_show(v) for v in value)
        return f"{len(value)} {type(value[0]).__name__} values" if value else "()"
    if isinstance(value, bool):
        return str(value).lower()
    if value is None:
        return "none"
    return str(value)


def run_reproduce(args: argparse.Namespace) -> int:
    if args.list:
        print("\n".join(list_lines()))
        return 0
    if args.name is None or args.out is None:
        raise SystemExit("navtrack reproduce: give NAME and --out DIR (or --list)")
    if args.runs is not None and args.runs < 0:
        raise SystemExit("navtrack reproduce: --runs must be >= 0")
    if args.workers is not None and args.scheduler is not None:
        raise SystemExit("navtrack reproduce: give at most one of --workers and --scheduler")
    exp = get_experiment(args.name)
    try:
        params = exp.default_params()
        if args.params is not None:
            values = read_parameter_file(args.params)
            params = apply_parameters(params, values, experiment=exp.name, source=str(args.params))
        params = apply_parameters(
            params, parse_assignments(args.assignments), experiment=exp.name, source="--set"
        )
    except ParameterError as exc:
        raise SystemExit(f"navtrack reproduce: {exc}") from None
    options = ReproduceOptions(
        out_dir=args.out,
        runs=args.runs,
        seed=args.seed,
        params=params,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.no_progress,
        inputs=tuple(args.input),
        figures=not args.no_figures,
        log=print,
    )
    results = reproduce(exp, options)
    for line in header_lines(results) + exp.summary_lines(results):
        print(line)
    print(f"wrote      {args.out / 'results.json'}, {args.out / 'tables.md'}")
    if "figures_error" in results:
        print(f"no figures {results['figures_error']}")
    return 0
