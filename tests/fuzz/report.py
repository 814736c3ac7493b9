"""Print the fuzz table: mutants per target x outcome, and every failure with its message.

Run from the repository: ``PYTHONPATH=src python tests/fuzz/report.py --per-operator 5``
(``--per-operator N`` mutants of each operator for each target, seeds 0..N-1; the CI test
runs a smaller, hypothesis-drawn share of the same mutants).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fuzz_mutations import OPERATORS
from fuzz_targets import FAILURES, OUTCOMES, TARGETS, Runner, run_mutant


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-operator", type=int, default=5, help="mutants per operator")
    parser.add_argument("--targets", nargs="*", default=list(TARGETS), help="targets to run")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    table: dict[str, Counter[str]] = {}
    failures: list[str] = []
    by_operator: dict[str, Counter[str]] = {op: Counter() for op in OPERATORS}
    clock = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, Runner() as runner:
        for name in args.targets:
            counts: Counter[str] = Counter()
            if TARGETS[name].seed(Path(tmp)) is None:
                print(f"{name}: seed not available (shared data?), skipped", file=sys.stderr)
                continue
            for op in OPERATORS:
                for seed in range(args.per_operator):
                    outcome, message, line = run_mutant(runner, name, op, seed, Path(tmp))
                    counts[outcome] += 1
                    by_operator[op][outcome] += 1
                    if outcome in FAILURES:
                        failures.append(
                            f"{name} {op} seed {seed} (line {line}): {outcome}: {message}"
                        )
            table[name] = counts
    width = max(len(n) for n in table)
    print(f"{'target':<{width}}  " + "  ".join(f"{o:>10}" for o in ("mutants", *OUTCOMES)))
    total: Counter[str] = Counter()
    for name, counts in table.items():
        total.update(counts)
        row = [sum(counts.values()), *(counts[o] for o in OUTCOMES)]
        print(f"{name:<{width}}  " + "  ".join(f"{v:>10}" for v in row))
    row = [sum(total.values()), *(total[o] for o in OUTCOMES)]
    print(f"{'all':<{width}}  " + "  ".join(f"{v:>10}" for v in row))
    print(f"({time.perf_counter() - clock:.0f} s)")
    print()
    width = max(len(op) for op in OPERATORS)
    print(f"{'operator':<{width}}  " + "  ".join(f"{o:>10}" for o in ("mutants", *OUTCOMES)))
    for op, counts in by_operator.items():
        row = [sum(counts.values()), *(counts[o] for o in OUTCOMES)]
        print(f"{op:<{width}}  " + "  ".join(f"{v:>10}" for v in row))
    for f in failures:
        print(f)
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
