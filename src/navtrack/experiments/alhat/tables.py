"""Tables and console lines of ``navtrack reproduce alhat``."""

from __future__ import annotations

from typing import Any

from navtrack.attitude.reconstruct import ESTIMATES

__all__ = ["summary_lines", "tables_markdown"]

#: Published numbers (paper 6). Text below eq. 5 and Figure 16: the correction lowered the
#: maximum scalar error of one Borrow Pit sequence from 0.26 to 0.18 deg and its standard
#: deviation from 0.06 to 0.03 deg. Instrument verification (Borrow Pit): LIDAR maximum pitch and
#: yaw errors 0.25 and 0.16 deg, camera 0.12 and 0.15 deg. Conclusions: expected attitude
#: performance 0.071 deg, maximum observed attitude error 0.33 deg.
PAPER_VALUES = {
    "max_scalar_error_before_deg": 0.26,
    "max_scalar_error_after_deg": 0.18,
    "std_scalar_error_before_deg": 0.06,
    "std_scalar_error_after_deg": 0.03,
    "lidar_max_pitch_deg": 0.25,
    "lidar_max_yaw_deg": 0.16,
    "camera_max_pitch_deg": 0.12,
    "camera_max_yaw_deg": 0.15,
    "expected_attitude_deg": 0.071,
    "max_observed_attitude_deg": 0.33,
}


def _fmt(v: Any, digits: int = 3) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


def _spread(s: dict[str, float] | None) -> str:
    if not s:
        return "—"
    return f"{s['median']:.3f} [{s['p05']:.3f}, {s['p95']:.3f}]"


def _regime_error_lines(reg: dict[str, Any], pv: dict[str, Any]) -> list[str]:
    """The regime's attitude errors against the truth and the LIDAR yaw/pitch check."""
    lines: list[str] = []
    lines += [
        "",
        "## Paper's method in the paper's regime: attitude error against the truth",
        "",
        "| estimate | mean deg | max deg | paper |",
        "|---|---|---|---|",
    ]
    for key, label in (
        ("weighted_eq7", "weighted sequences (eqs. 6-7)"),
        ("longest_sequence_corrected", "longest sequence's corrected start only (eq. 5)"),
    ):
        e = reg[key]
        lines.append(
            f"| {label} | {_spread(e['mean_deg'])} | {_spread(e['max_deg'])} | expected "
            f"{pv['expected_attitude_deg']}, max observed {pv['max_observed_attitude_deg']} |"
        )
    lines += [
        "",
        f"Eq. 7 readings: the absolute (printed) and relative axis-angle averages part by more "
        f"than 0.01° at {reg['average_readings_differ_samples']} samples (largest gap "
        f"{reg['average_readings_max_gap_deg']:.2g}°); sequences with σ0 floored: "
        f"{reg['sigma0_floored']}.",
    ]
    lid = reg["lidar"]
    lines += [
        "",
        "## Paper's method in the paper's regime: LIDAR and camera yaw/pitch (eqs. 10-11)",
        "",
        "Maximum absolute error per run, deg. Yaw from the shift along the LIDAR y axis (eq. 10, "
        "a rotation about x), pitch from the shift along x (eq. 11, a rotation about y). "
        f"LIDAR frames: {lid['frames_ok']} fitted, {lid['frames_off_dem']} off the DEM, "
        f"{lid['frames_not_converged']} not converged.",
        "",
        "| source | yaw (eq. 10) | pitch (eq. 11) | paper yaw | paper pitch |",
        "|---|---|---|---|---|",
        f"| LIDAR DEM correlation | {_spread(lid['lidar_max_abs_yaw_deg'])} | "
        f"{_spread(lid['lidar_max_abs_pitch_deg'])} | {pv['lidar_max_yaw_deg']} | "
        f"{pv['lidar_max_pitch_deg']} |",
        f"| camera fixes | {_spread(lid['camera_max_abs_yaw_deg'])} | "
        f"{_spread(lid['camera_max_abs_pitch_deg'])} | {pv['camera_max_yaw_deg']} | "
        f"{pv['camera_max_pitch_deg']} |",
        f"| truth (simulation only) | {_spread(lid['true_max_abs_yaw_deg'])} | "
        f"{_spread(lid['true_max_abs_pitch_deg'])} | — | — |",
        "",
        f"RMS of LIDAR minus truth per run: {_spread(lid['lidar_minus_true_rms_deg'])} deg.",
        "",
    ]
    return lines


def _fig16_lines(reg: dict[str, Any]) -> list[str]:
    pv = PAPER_VALUES
    lines = [
        "## Paper's method in the paper's regime: Fig. 16 statistic (e_s at the fixes)",
        "",
        f"{reg['runs']} simulated recordings ("
        + ", ".join(f"{k} {v}" for k, v in reg["settings"].items())
        + "); navtrack columns are median [5 %, 95 %] over the runs.",
        "",
        "| e_s statistic | paper (Borrow Pit) | longest sequence of each run | every sequence |",
        "|---|---|---|---|",
    ]
    for key, label in (
        ("max_before_deg", "max before correction, deg"),
        ("max_after_deg", "max after correction, deg"),
        ("std_before_deg", "std before correction, deg"),
        ("std_after_deg", "std after correction, deg"),
    ):
        paper = pv[key.replace("max_", "max_scalar_error_").replace("std_", "std_scalar_error_")]
        lines.append(
            f"| {label} | {paper} | {_spread(reg['longest_sequence'][key])} | "
            f"{_spread(reg['all_sequences'][key])} |"
        )
    ls, al = reg["longest_sequence"], reg["all_sequences"]
    n_ok = reg["status"].get("ok", 0)
    lines += [
        f"| correction lowered the max | yes | {ls['max_lowered']} of {n_ok} | "
        f"{al['max_lowered']} of {al['count']} |",
        f"| correction lowered the std | yes | {ls['std_lowered']} of {n_ok} | "
        f"{al['std_lowered']} of {al['count']} |",
        f"| sequence length, s | ~200 | {_spread(ls['length_s'])} | — |",
        "",
        "Per sequence, first run:",
        "",
        "| sequence | fixes | length s | max before deg | max after deg | std before deg "
        "| std after deg |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in reg["first_run_sequences"]:
        lines.append(
            f"| {row['sequence']} | {row['fixes']} | {_fmt(row['length_s'])} | "
            f"{row['max_before_deg']:.3f} | {row['max_after_deg']:.3f} | "
            f"{row['std_before_deg']:.3f} | {row['std_after_deg']:.3f} |"
        )
    return lines + _regime_error_lines(reg, pv)


def _extension_lines(ext: dict[str, Any]) -> list[str]:
    lines = [
        "## Extensions (not the paper's method): one recording in the paper's regime",
        "",
        "Calibration, filter and smoother (the paper's future work) on the same fixes; "
        "attitude error against the truth.",
        "",
        "| estimate | mean deg | max deg |",
        "|---|---|---|",
    ]
    paper = ext.get("paper", {}).get("weighted_eq7")
    if paper:
        lines.append(
            f"| paper: weighted sequences (eqs. 6-7) | {_fmt(paper['mean_deg'])} | "
            f"{_fmt(paper['max_deg'])} |"
        )
    for name, e in ext.get("extensions", {}).items():
        lines.append(f"| {name} | {_fmt(e['mean_deg'])} | {_fmt(e['max_deg'])} |")
    return [*lines, ""]


def tables_markdown(results: dict[str, Any]) -> str:
    lines = ["# Paper 6 (ALHAT trajectory reconstruction)", ""]
    reg = results.get("regime", {})
    if reg.get("status", {}).get("ok"):
        lines += _fig16_lines(reg)
    else:
        lines += [f"Paper's regime not run: {_fmt(reg.get('status'))}", ""]
    if results.get("regime_extensions", {}).get("extensions"):
        lines += _extension_lines(results["regime_extensions"])
    lines += ["## BROAD's real MEMS gyro (its own recordings, simulated wide camera)", ""]
    lines += ["Attitude error against the optical truth (movement samples).", ""]
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
    reg = results.get("regime", {})
    if reg.get("status", {}).get("ok"):
        ls = reg["longest_sequence"]
        out.append(
            "paper's regime, longest sequence (median of runs): e_s max "
            f"{ls['max_before_deg']['median']:.3f} -> {ls['max_after_deg']['median']:.3f} deg, "
            f"std {ls['std_before_deg']['median']:.3f} -> {ls['std_after_deg']['median']:.3f} "
            "deg (paper 0.26 -> 0.18, 0.06 -> 0.03)"
        )
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
    return out
