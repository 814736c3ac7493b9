"""Tables and console lines of ``navtrack reproduce alhat``."""

from __future__ import annotations

from typing import Any

from navtrack.attitude.reconstruct import ESTIMATES

__all__ = ["summary_lines", "tables_markdown"]

#: Published numbers (paper 6, text below eq. 5, Figure 16): the correction lowered the maximum
#: scalar error of one Borrow Pit sequence from 0.26 to 0.18 deg and its standard deviation from
#: 0.06 to 0.03 deg.
PAPER_VALUES = {
    "max_scalar_error_before_deg": 0.26,
    "max_scalar_error_after_deg": 0.18,
    "std_scalar_error_before_deg": 0.06,
    "std_scalar_error_after_deg": 0.03,
}


def _fmt(v: Any, digits: int = 3) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


def tables_markdown(results: dict[str, Any]) -> str:
    lines = ["# Paper 6 (ALHAT trajectory reconstruction) on BROAD", ""]
    lines += ["## Attitude error against the optical truth (movement samples)", ""]
    keys = [*ESTIMATES, "paper_correction_paper_literal", "paper_correction_mean_rotvec"]
    lines += [
        "| trial | estimate | mean deg | max deg | rms deg | p95 deg |",
        "|---|---|---|---|---|---|",
    ]
    for name, tr in results.get("trials", {}).items():
        for k in keys:
            if k in tr:
                s = tr[k]
                lines.append(
                    f"| {name} | {k} | {_fmt(s['mean_deg'])} | {_fmt(s['max_deg'])} | "
                    f"{_fmt(s['rms_deg'])} | {_fmt(s['p95_deg'])} |"
                )
    lines += ["", "## Truncated series against the closed form (whole trial)", ""]
    lines += [
        "| trial | order 1 rad | order 2 rad | order 3 rad | bound Σθ⁵/480 | closed ms "
        "| series ms |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, tr in results.get("trials", {}).items():
        s = tr["series"]
        lines.append(
            f"| {name} | {_fmt(s['order1_max_rad'])} | {_fmt(s['order2_max_rad'])} | "
            f"{_fmt(s['order3_max_rad'])} | {_fmt(s['order3_bound_rad'])} | "
            f"{_fmt(s['propagate_closed_ms'])} | {_fmt(s['propagate_series3_ms'])} |"
        )
    lines += ["", "## Calibration and timing", ""]
    lines += [
        "| trial | bias rad/s | scale | time offset s | gyro-optical lag s | fix rms deg |",
        "|---|---|---|---|---|---|",
    ]
    for name, tr in results.get("trials", {}).items():
        c = tr["calibration"]
        lines.append(
            f"| {name} | {', '.join(_fmt(b) for b in c['bias_rad_s'])} | "
            f"{', '.join(_fmt(b) for b in c['scale'])} | {_fmt(c['time_offset_s'])} | "
            f"{_fmt(tr['timing_offset_check']['gyro_optical_lag_s'])} | {_fmt(c['rms_deg'])} |"
        )
    r = results.get("ransac", {})
    if r.get("runs"):
        lines += ["", "## RANSAC-SVD scenes (Monte Carlo)", ""]
        lines += [
            "| runs | rays | outliers | all rejected | outliers accepted | inliers rejected "
            "| error mean rad | oracle mean rad | max from oracle rad | ms |"
        ]
        lines += ["|---|---|---|---|---|---|---|---|---|---|"]
        lines.append(
            f"| {r['runs']} | {r['n_rays']} | {r['outlier_fraction']} | "
            f"{r['all_outliers_rejected']} | "
            f"{r['outliers_accepted']} | {r['inliers_rejected']} | {_fmt(r['error_mean_rad'])} | "
            f"{_fmt(r['oracle_error_mean_rad'])} | {_fmt(r['from_oracle_max_rad'])} | "
            f"{_fmt(r['fix_ms_median'])} |"
        )
    lines += [
        "",
        "Paper (Borrow Pit sequence, Figure 16): "
        + ", ".join(f"{k} {v}" for k, v in PAPER_VALUES.items()),
        "",
    ]
    if results.get("trials_skipped"):
        lines += ["Skipped: " + "; ".join(results["trials_skipped"]), ""]
    return "\n".join(lines)


def summary_lines(results: dict[str, Any]) -> list[str]:
    out = []
    for k in ESTIMATES:
        if k in results:
            out.append(
                f"{k:<17} mean {results[k]['mean_deg']:.3f} deg, "
                f"max {results[k]['max_deg']:.3f} deg"
            )
    for name, tr in results.get("trials", {}).items():
        s = tr["series"]
        out.append(
            f"{name}: series order 3 vs closed {s['order3_max_rad']:.2e} rad, "
            f"propagation {s['propagate_closed_ms']:.1f} ms, fixes {tr['fixes']['status']}, "
            f"time offset {tr['calibration']['time_offset_s'] * 1e3:.2f} ms"
        )
    r = results.get("ransac", {})
    if r.get("runs"):
        out.append(
            f"ransac: {r['all_outliers_rejected']}/{r['runs']} scenes with every outlier rejected, "
            f"{r['fix_ms_median']:.2f} ms per fix"
        )
    if "pose_trajectory" in results:
        out.append(f"pose trajectory {results['pose_trajectory']}")
    return out
