"""Choice and judgement of PPP's range-error model (``sigma_model_m``, ``model_correlation_s``).

Chooses on four 3-hour NIST sessions of 2023-01-01 (00, 06, 12, 18 h; WUM's 30 s clock file and
``igs05.atx``), with SEPT as a constraint: the pair of the grid with the smallest mean of the
four median errors (from 5 minutes on) among those whose error lies inside the formal 95 %
ellipsoid at >= 90 % of the epochs from 30 minutes on in each of the four sessions, and from 5
minutes on for SEPT. Then judges the default on the other four sessions, all eight sessions
with only the 5-minute SP3 clocks, ARL1 and SEPT. RTKLIB's side of the same data is in
``bench_ppp.py`` (``docs/ppp.md``, method notes).

Usage (``DIR`` holds the NIST files, see ``bench_ppp.py``)::

    PYTHONPATH=src python benchmarks/eval_ppp_model.py --data DIR
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np

from bench_ppp import CASES, NIST_REF, Case
from navtrack.geodesy import ecef_to_enu
from navtrack.gnss.antex import Antex, read_antex
from navtrack.gnss.ppp import PppConfig, PppResult, solve_ppp
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rinex_clock import read_clock
from navtrack.gnss.sp3 import read_sp3

SIGMAS_M = (0.01, 0.015, 0.02, 0.03)
TAUS_S = (300.0, 600.0, 900.0, 1800.0, 3600.0)
CHOOSE_H = (0, 6, 12, 18)


def _score(res: PppResult, ref: tuple[float, float, float]) -> tuple[float, float, float]:
    """Median 3-D error from 5 min (m), share inside the 95 % bound from 5 and 30 min (%)."""
    ok = res.updated
    t = res.t_gps_s[ok] - res.t_gps_s[ok][0]
    err = np.linalg.norm(ecef_to_enu(res.pos_m[ok], np.asarray(ref)), axis=1)
    inside = res.inside_bound(np.asarray(ref))[ok]
    late = inside[t >= 1800.0]
    return (
        float(np.median(err[t >= 300.0])),
        100.0 * float(inside[t >= 300.0].mean()),
        100.0 * float(late.mean()) if late.size else float("nan"),
    )


def _shared(case: Case, cfg: PppConfig, atx: Antex | None) -> tuple[float, float, float]:
    """Score of a shared-data case (no clock file)."""
    obs, nav, sp3, _, ref = case
    return _score(solve_ppp(read_obs(obs), [read_nav(nav)], read_sp3(sp3), cfg, antex=atx), ref)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, required=True)
    d = ap.parse_args(argv).data
    nav = [read_nav(d / "BRDC00IGS_R_20230010000_01D_MN.rnx")]
    sp3 = read_sp3(d / "WUM0MGXFIN_20230010000_01D_05M_ORB.SP3")
    clk = sp3.with_clock(read_clock(d / "WUM0MGXFIN_20230010000_01D_30S_CLK.CLK"))
    atx = read_antex(d / "igs05.atx")
    sessions = {h: read_obs(d / f"NIST_{h:02d}h_3h.rnx") for h in range(0, 24, 3)}
    best: tuple[float, PppConfig] | None = None
    print("sigma_model_m tau_s | SEPT median, inside 5 min | chooser sessions: median, inside 30")
    for sigma, tau in itertools.product(SIGMAS_M, TAUS_S):
        cfg = PppConfig(sigma_model_m=sigma, model_correlation_s=tau)
        sept = _shared(CASES["SEPT"], cfg, None)
        scores = [
            _score(solve_ppp(sessions[h], nav, clk, cfg, antex=atx), NIST_REF) for h in CHOOSE_H
        ]
        mean_med = float(np.mean([s[0] for s in scores]))
        cells = ", ".join(f"{s[0]:.3f} m {s[2]:.0f} %" for s in scores)
        print(
            f"{sigma:.3f} {tau:6.0f} | {sept[0]:.3f} m {sept[1]:.0f} % | {cells} "
            f"| mean {mean_med:.4f}"
        )
        if (
            sept[1] >= 90
            and all(s[2] >= 90 for s in scores)
            and (best is None or mean_med < best[0])
        ):
            best = (mean_med, cfg)
    if best is not None:
        cfg = best[1]
        print(
            f"chosen: sigma_model_m {cfg.sigma_model_m}, "
            f"model_correlation_s {cfg.model_correlation_s}"
        )
    print("default judged | median from 5 min, inside from 5 / 30 min")
    cfg = PppConfig()
    for h, obs in sessions.items():
        for name, products in (("30 s clocks", clk), ("SP3 clocks", sp3)):
            s = _score(solve_ppp(obs, nav, products, cfg, antex=atx), NIST_REF)
            role = "chose" if h in CHOOSE_H and products is clk else "judged"
            print(f"NIST {h:02d} h {name} ({role}) | {s[0]:.3f} m, {s[1]:.0f} / {s[2]:.0f} %")
    for name in ("ARL1", "SEPT"):
        s = _shared(CASES[name], cfg, atx)
        print(f"{name} --antex (judged) | {s[0]:.3f} m, {s[1]:.0f} / {s[2]:.0f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
