"""``navtrack reproduce raim-fcm``: paper 2 (Gu et al. 2019) on the experiment contract.

1. Monte Carlo runs: fault injection on the shared real data for every method
   (:func:`~navtrack.experiments.raim_fcm.study.injection_run`), summarized as rates;
2. the ``extra`` step: the paper's numeric example
   (:func:`~navtrack.experiments.raim_fcm.example.paper_example`) and the protection levels of
   every method against the actual errors on all clean epochs of each station (the data of the
   Stanford diagrams), and on the whole days given with ``--input``
   (:mod:`~navtrack.experiments.raim_fcm.wholeday`);
3. tables, console lines, figures (:mod:`navtrack.plots.integrity`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.experiments.contract import (
    Experiment,
    ExperimentContext,
    ExtraResult,
    Outcome,
    shared_data_dir,
)
from navtrack.experiments.raim_fcm.example import paper_example
from navtrack.experiments.raim_fcm.study import (
    RaimFcmParams,
    injection_run,
    raim_config,
    rtklib_live_raim,
    station_data,
    summarize_study,
)
from navtrack.experiments.raim_fcm.wholeday import whole_day_protection
from navtrack.geodesy import ecef_to_enu
from navtrack.integrity.raim import RaimStatus, monitor
from navtrack.plots import integrity as plots

__all__ = ["EXPERIMENT", "RaimFcmExperiment", "clean_protection"]

_RunResult = dict[str, Any]
_RATES = ("detection", "identification", "wrong_exclusion")


def _gnss_dir() -> str:
    return str(shared_data_dir(required=True) / "gnss")


def clean_protection(params: RaimFcmParams, gnss_dir: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """Protection levels against actual errors on every clean epoch, per station and method.

    Returns
    -------
    results : dict
        ``{station: {method: {"epochs", "bounded_h", "bounded_v", "hpl_median_m",
        "vpl_median_m", "exclusion", "alert"}}}`` (fractions of the epochs with a protection
        level).
    artifacts : dict
        ``{station: {method: (err_h, hpl, err_v, vpl)}}`` arrays for the Stanford diagrams.
    """
    res: dict[str, Any] = {}
    art: dict[str, Any] = {}
    for name in params.stations:
        data = station_data(gnss_dir, name, params.iono)
        res[name], art[name] = {}, {}
        for m in params.methods:
            final, _, integ = monitor(
                data.meas, data.clean, data.config, raim_config(params, m, data.variance_factor)
            )
            enu = ecef_to_enu(final.x[:, :3], data.ref_xyz_m)
            eh, ev = np.hypot(enu[:, 0], enu[:, 1]), np.abs(enu[:, 2])
            has = np.isfinite(integ.hpl_m)
            n = max(int(has.sum()), 1)
            res[name][m] = {
                "epochs": int(has.sum()),
                "bounded_h": float(np.sum(eh[has] <= integ.hpl_m[has]) / n),
                "bounded_v": float(np.sum(ev[has] <= integ.vpl_m[has]) / n),
                "hpl_median_m": float(np.median(integ.hpl_m[has])) if has.any() else None,
                "vpl_median_m": float(np.median(integ.vpl_m[has])) if has.any() else None,
                "exclusion": float(np.mean(integ.excluded.any(axis=1))),
                "alert": float(np.mean(integ.status == RaimStatus.ALERT)),
            }
            art[name][m] = (eh, integ.hpl_m, ev, integ.vpl_m)
    return res, art


class RaimFcmExperiment(Experiment[RaimFcmParams, _RunResult]):
    """RAIM by fuzzy clustering and the classical methods: paper example, fault injection on
    real data, protection levels."""

    name = "raim-fcm"
    description = (
        "Paper 2: RAIM by fuzzy clustering (Gu et al. 2019) vs chi2/LOO/FDE/SS on real data"
    )
    params_type = RaimFcmParams
    default_runs = 5

    def run_one(self, params: RaimFcmParams, rng: np.random.Generator) -> _RunResult:
        return injection_run(params, rng, _gnss_dir())

    def summarize(self, params: RaimFcmParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        return {
            "paper": "Gu et al., RAIM algorithm based on fuzzy clustering analysis, CMES 2019",
            "injection": summarize_study(params, runs),
        }

    def extra(self, params: RaimFcmParams, context: ExperimentContext) -> ExtraResult:
        protection, art = clean_protection(params, _gnss_dir())
        example = paper_example(params.fcm_m, params.fcm_stop)
        results = {"example": example, "clean_protection": protection}
        methods = [m for m in params.methods if m != "rtklib"]
        day, day_art = whole_day_protection(context.inputs, methods)
        if day:
            results["whole_day"] = day
            art.update(day_art)
        if "ARL1" in params.stations:
            work = context.out_dir / "rtklib_live"
            work.mkdir(parents=True, exist_ok=True)
            results["rtklib_live"] = rtklib_live_raim(params, context.rng, _gnss_dir(), work)
        return ExtraResult(results, art)

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(self, outcome: Outcome[RaimFcmParams, _RunResult], out_dir: Path) -> list[Path]:
        paths = [plots.membership_figure_file(outcome.results["example"], out_dir)]
        paths += plots.stanford_figure_files(outcome.artifacts, out_dir)
        return paths

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.3f}"


def _example_lines(ex: dict[str, Any]) -> list[str]:
    out = [
        "## Paper example (section 5)",
        "",
        "| case | injected | FCM | hierarchical | max abs(F - printed) |",
        "|---|---|---|---|---|",
    ]
    for case in ("single", "double"):
        c = ex[case]
        out.append(
            f"| {case} | {c['injected']} | {c['fcm_gross_errors']} | "
            f"{c['hierarchical_gross_errors']} | {c['max_abs_difference']:.4f} |"
        )
    scan = ex.get("fuzziness_scan")
    if scan:
        out += [
            "",
            "Two faults (4 and 7) against the FCM weighting exponent m: satellites named "
            "(iterations), stopping on the memberships or on the cluster centres.",
            "",
            "| m | memberships | centres |",
            "|---|---|---|",
        ]
        for row in scan:
            cells = [
                f"{row[s]['fcm_gross_errors']} ({row[s]['iterations']})"
                for s in ("memberships", "centres")
            ]
            out.append(f"| {row['m']:g} | {cells[0]} | {cells[1]} |")
    return [*out, ""]


def _injection_lines(name: str, st: dict[str, Any]) -> list[str]:
    methods = list(next(iter(st["cases"].values())))
    out = [f"## {name}: fault injection (variance factor {st['variance_factor']:.3f})", ""]
    out.append("| case | " + " | ".join(f"{m} det/id/wrong" for m in methods) + " |")
    out.append("|---|" + "---|" * len(methods))
    for case, d in st["cases"].items():
        cells = [
            "/".join(f"{d[m][r]:.2f}" for r in _RATES) + f" (e95 {d[m]['err_h_p95_m']:.1f})"
            for m in methods
        ]
        out.append(f"| {case} | " + " | ".join(cells) + " |")
    return [*out, ""]


def _rtklib_live_lines(live: dict[str, Any]) -> list[str]:
    out = [
        "## ARL1 single faults: RTKLIB 2.4.3 rnx2rtkp RAIM FDE (live) vs navtrack fde",
        "",
        "| bias (m) | trials | RTKLIB id / wrong / excl | fde id / wrong / excl "
        "| RTKLIB e95 H (m) | fde e95 H (m) |",
        "|---|---|---|---|---|---|",
    ]
    for b, d in live.items():
        r, f = d["rtklib"], d["fde"]
        out.append(
            f"| {b} | {r['trials']} | {r['identification']:.2f} / {r['wrong_exclusion']:.2f}"
            f" / {r['exclusion']:.2f} | {f['identification']:.2f} / "
            f"{f['wrong_exclusion']:.2f} / {f['exclusion']:.2f} | {r['err_h_p95_m']:.1f} "
            f"| {f['err_h_p95_m']:.1f} |"
        )
    return [*out, ""]


def _protection_lines(prot: dict[str, Any]) -> list[str]:
    out = ["## Clean epochs: protection levels against actual errors", ""]
    out += [
        "| station | method | epochs | HPL bounds | VPL bounds | median HPL | median VPL "
        "| exclusions |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, d in prot.items():
        for m, v in d.items():
            out.append(
                f"| {name} | {m} | {v['epochs']} | {v['bounded_h']:.4f} "
                f"| {v['bounded_v']:.4f} | {_fmt(v['hpl_median_m'])} "
                f"| {_fmt(v['vpl_median_m'])} | {v['exclusion']:.4f} |"
            )
    return [*out, ""]


def _whole_day_lines(day: dict[str, Any]) -> list[str]:
    out = [
        "## Whole days: misleading information and availability",
        "",
        "Misleading information (MI): epochs with status ok or excluded whose error exceeds "
        "the protection level. Availability: HPL <= 40 m and VPL <= 35 m (LPV-200), and "
        "HPL <= 40 m alone, over all epochs.",
        "",
        "| run | method | epochs | ok / excl / alert / unav | MI H / V | median HPL / VPL "
        "| 95 % error H / V | VPL <= 35 m | LPV-200 | horizontal |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for key, d in day.items():
        for m, v in d.items():
            s = v["statuses"]
            out.append(
                f"| {key} | {m} | {v['epochs']} | {s['ok']} / {s['excluded']} / "
                f"{s['alert']} / {s['unavailable']} | {v['mi_h']} / {v['mi_v']} | "
                f"{_fmt(v['hpl_median_m'])} / {_fmt(v['vpl_median_m'])} | "
                f"{_fmt(v['err_h_p95_m'])} / {_fmt(v['err_v_p95_m'])} | "
                f"{v['vpl_le_val']:.3f} | {v['availability_v']:.3f} | "
                f"{v['availability_h']:.3f} |"
            )
    return [*out, ""]


def tables_markdown(results: dict[str, Any]) -> str:
    """Markdown: the paper example, fault-injection rates, the live RTKLIB comparison,
    clean-data protection levels and the whole days."""
    out = ["# RAIM by fuzzy clustering (paper 2)", ""]
    if results.get("example"):
        out += _example_lines(results["example"])
    for name, st in results.get("injection", {}).items():
        out += _injection_lines(name, st)
    live = results.get("rtklib_live", {})
    if live and "skipped" not in live:
        out += _rtklib_live_lines(live)
    if results.get("clean_protection"):
        out += _protection_lines(results["clean_protection"])
    if results.get("whole_day"):
        out += _whole_day_lines(results["whole_day"])
    return "\n".join(out)


def summary_lines(results: dict[str, Any]) -> list[str]:
    """Console lines: the example's classes and, per station, the identification rates of
    single and double faults of 10 m or more."""
    lines = []
    ex = results.get("example")
    if ex:
        lines.append(
            f"paper example  FCM {ex['single']['fcm_gross_errors']} / "
            f"{ex['double']['fcm_gross_errors']}, hierarchical "
            f"{ex['single']['hierarchical_gross_errors']} / "
            f"{ex['double']['hierarchical_gross_errors']}"
        )
    for key, d in results.get("whole_day", {}).items():
        lines.append(
            f"{key:<14} MI (H/V) " + " ".join(f"{m} {v['mi_h']}/{v['mi_v']}" for m, v in d.items())
        )
    live = results.get("rtklib_live", {})
    if live and "skipped" not in live:
        lines.append(
            "ARL1 live   single-fault identification RTKLIB / fde "
            + " ".join(
                f"{b} m {d['rtklib']['identification']:.2f}/{d['fde']['identification']:.2f}"
                for b, d in live.items()
            )
        )
    for name, st in results.get("injection", {}).items():
        for k in (1, 2):
            keys = [
                c for c in st["cases"] if c.startswith(f"k{k}_") and float(c.split("_b")[1]) >= 10
            ]
            if not keys:
                continue
            methods = list(st["cases"][keys[0]])
            ident = {m: min(st["cases"][c][m]["identification"] for c in keys) for m in methods}
            lines.append(
                f"{name:<10} k={k} >=10 m  min identification "
                + " ".join(f"{m} {v:.2f}" for m, v in ident.items())
            )
        clean = st["cases"].get("clean")
        if clean:
            lines.append(
                f"{name:<10} clean      wrong exclusions "
                + " ".join(f"{m} {v['wrong_exclusion']:.3f}" for m, v in clean.items())
            )
    return lines


#: The registered instance (``navtrack.experiments.EXPERIMENTS["raim-fcm"]``).
EXPERIMENT = RaimFcmExperiment()
