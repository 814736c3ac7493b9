"""Paper 3's timing claim: SD-CMSJPDA / sequential MSJPDA time per step, with numba and without.

Run: ``PYTHONPATH=src python benchmarks/bench_sdcmsjpda_ratio.py [--scan-sets 2] [--repeat 5]
[--seed 7]``.

The paper reports 28.2 ms against 25.1 ms per step (ratio 1.12) on a 2.0 GHz PC; only the
ratio is compared. :func:`navtrack.experiments.sdcmsjpda.timing.both_paths` simulates
``--scan-sets`` scan sets per P_D of the study's scenario, runs sequential MSJPDA, the literal
SD-CMSJPDA and the ML-fused reading on each set in turn (order rotated from set to set), in this
process (numba as installed) and then in a child process with ``NAVTRACK_NO_NUMBA=1`` (the NumPy
paths). Printed: the load average before and after; per path the median CPU ms per step of
each tracker and the median of the paired ratios to sequential MSJPDA on the same scan set,
the paper's ratio beside. ``navtrack reproduce sdcmsjpda`` writes the same table into
``tables.md`` (``--set timing_repeat=N``).
"""

from __future__ import annotations

import argparse
import os

from navtrack.experiments.sdcmsjpda.scenario import SdCmsjpdaParams
from navtrack.experiments.sdcmsjpda.timing import both_paths, ratio_markdown


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scan-sets", type=int, default=2, help="scan sets per P_D")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    print(f"load average before {os.getloadavg()}")
    timing = both_paths(SdCmsjpdaParams(), args.scan_sets, args.repeat, args.seed)
    print(
        f"paper-3 scenario, {args.scan_sets} scan sets per P_D (seed {args.seed}), 140 steps; "
        f"CPU ms per fusion step, medians of {timing['this_process']['pairs']} runs per tracker"
    )
    print("\n".join(ratio_markdown(timing)))
    print(f"load average after {os.getloadavg()}")


if __name__ == "__main__":
    main()
