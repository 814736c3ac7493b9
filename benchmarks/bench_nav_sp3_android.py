"""Read times of navigation, SP3 and Android files: navtrack against georinex 1.16.2.

Run: ``PYTHONPATH=src python benchmarks/bench_nav_sp3_android.py [--repeat N]``. Prints the
median of N in-process runs of navtrack's reader per shared file, one run of georinex
(``georinex.load`` / ``georinex.load_sp3``) where it reads the file, and the ratio.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
GNSS = ROOT.parent / "shared" / "data" / "gnss"

NAV = (
    "rtklib_gsi0759/07590920.05n",
    "gpstk_arl1/arlm2000.15n",
    "cssrlib_sept/SEPT078M.21P",
    "gogps_yamatogawa/brdc0060.10n",
    "gogps_yamatogawa/yamatogawa_rover.nav",
    "google_gnsslogger/hour2350.16n",
)
SP3 = (
    "cssrlib_sept/COD0MGXFIN_20210780000_01D_05M_ORB.SP3",
    "gpstk_arl1/test_input_sp3_nav_2015_200.sp3",
)
ANDROID = ("google_gnsslogger/pseudoranges_log_2016_08_22_14_45_50.txt",)


def _median_s(fn: Callable[[], Any], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    from navtrack.gnss.android import read_gnsslogger
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.sp3 import read_sp3

    try:
        import georinex
    except ImportError:
        georinex = None

    read_nav(GNSS / NAV[0])  # warm-up: imports pandas
    print(f"{'file':<48} {'navtrack ms':>12} {'georinex ms':>12} {'ratio':>7}")
    jobs: list[tuple[str, Callable[[Path], Any], Callable[[Path], Any] | None]] = []
    peer_nav = peer_sp3 = None
    if georinex is not None:
        peer_nav = georinex.load

        def peer_sp3(p: Path) -> Any:
            return georinex.load_sp3(p, None)

    jobs += [(n, read_nav, peer_nav) for n in NAV]
    jobs += [(n, read_sp3, peer_sp3) for n in SP3]
    jobs += [(n, read_gnsslogger, None) for n in ANDROID]
    for name, ours, peer in jobs:
        path = GNSS / name
        t_ours = _median_s(lambda ours=ours, path=path: ours(path), args.repeat)
        t_peer = float("nan")
        if peer is not None:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t_peer = _median_s(lambda peer=peer, path=path: peer(path), 1)
        ratio = t_peer / t_ours
        print(f"{Path(name).name:<48} {t_ours * 1e3:12.1f} {t_peer * 1e3:12.1f} {ratio:7.1f}")


if __name__ == "__main__":
    main()
