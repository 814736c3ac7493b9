"""``navtrack reproduce NAME --out DIR``: rerun a seed paper's experiment."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def register(subparsers: Any) -> None:
    from navtrack.experiments import EXPERIMENTS

    cmd = subparsers.add_parser(
        "reproduce",
        help="reproduce a seed paper's experiment (tables, figures, results.json)",
        description="Run a registered reproduction: seeded Monte Carlo runs (resumable, through "
        "Dask when installed), then DIR/results.json, DIR/tables.md and PNG figures. "
        f"Experiments: {', '.join(sorted(EXPERIMENTS))}.",
    )
    cmd.add_argument("name", help="experiment name", choices=sorted(EXPERIMENTS))
    cmd.add_argument("--out", type=Path, required=True, help="output directory")
    cmd.add_argument("--runs", type=int, help="Monte Carlo runs (default: the experiment's)")
    cmd.add_argument("--seed", type=int, default=0, help="root seed (default 0)")
    cmd.add_argument("--workers", type=int, help="start a local Dask cluster with N workers")
    cmd.add_argument("--scheduler", help="address of an existing Dask scheduler (tcp://...)")
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


def run_reproduce(args: argparse.Namespace) -> int:
    from navtrack.experiments import ReproduceOptions, get_experiment, reproduce

    if args.runs is not None and args.runs < 0:
        raise SystemExit("navtrack reproduce: --runs must be >= 0")
    if args.workers is not None and args.scheduler is not None:
        raise SystemExit("navtrack reproduce: give at most one of --workers and --scheduler")
    options = ReproduceOptions(
        out_dir=args.out,
        runs=args.runs,
        seed=args.seed,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.no_progress,
        inputs=tuple(args.input),
        figures=not args.no_figures,
    )
    results = reproduce(args.name, options)
    module = get_experiment(args.name)
    counts = results.get("run_counts", {})
    print(f"experiment {args.name}: {results.get('runs')} runs, seed {args.seed}")
    print(f"backend    {results.get('backend')} — {results.get('backend_note', '')}")
    print(
        f"runs       ok {counts.get('ok', 0)}, error {counts.get('error', 0)}, "
        f"resumed from checkpoints {counts.get('resumed', 0)}"
    )
    for line in getattr(module, "summary_lines", lambda r: [])(results):
        print(line)
    print(f"wrote      {args.out / 'results.json'}, {args.out / 'tables.md'}")
    for fig in results.get("figures", []):
        print(f"figure     {fig}")
    return 0
