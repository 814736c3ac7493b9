"""Tables of the ARI reproduction in the paper's own regimes (paper 5, Tables 1–5).

Carrier-phase strips (:mod:`navtrack.experiments.ari.carrier`) beside Tables 1–3, the
navigation-grade INS series (:mod:`navtrack.experiments.ari.ins`) beside Tables 4–5, both
forms of the variance components side by side, and a truth for every printed column
(:func:`navtrack.experiments.ari.truths.printed_truths`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from navtrack.experiments.ari.printed import PAPER_TABLE1, PAPER_TABLE2, PAPER_TABLES, fmt

__all__ = ["regime_lines"]

_GPS = PAPER_TABLES["GPS (Table 1 rms strips 3,4,5 / Table 3), m, 0.6 s, ARI(5,2)"]
_COLS = ("e_m", "n_m", "u_m")
_FITS = (("exact", "exact"), ("paper_redundancy", "paper, redundancy VCE"))
_FITS_F = (*_FITS, ("paper_forstner", "paper, Förstner VCE"))


def _order(rec: dict[str, Any] | None) -> str:
    return "–" if not rec else f"({rec['order'][0]},{rec['order'][1]})"


def _by_strip(rows: Sequence[dict[str, Any]]) -> dict[tuple[str, int], dict[str, dict[str, Any]]]:
    out: dict[tuple[str, int], dict[str, dict[str, Any]]] = {}
    for row in rows:
        out.setdefault((row["source"], row["strip"]), {})[row["column"]] = row
    return out


def _cells(cols: dict[str, dict[str, Any]], fit: str, key: str, digits: int = 3) -> str:
    return " / ".join(fmt((cols.get(c, {}).get(fit) or {}).get(key), digits) for c in _COLS)


def _carrier_lines(results: dict[str, Any]) -> list[str]:
    rows = results.get("carrier") or []
    skipped = results.get("carrier_skipped") or []
    if not rows:
        return ["", "No carrier-phase series: " + ("; ".join(skipped) or "switched off.")]
    strips = _by_strip(rows)
    return (
        _carrier_series_lines(rows, skipped)
        + _carrier_table1(strips)
        + _carrier_table2(strips)
        + _carrier_table3(strips)
        + _carrier_order_lines(rows)
    )


def _carrier_series_lines(rows: list[dict[str, Any]], skipped: list[str]) -> list[str]:
    """What the carrier-phase series are: one row per source."""
    rp = "reweighted" if rows[0]["robust_process"] else "not reweighted"
    lines = [
        "",
        "## Paper Tables 1–3 in the paper's regime: navtrack's carrier-phase positions",
        "",
        "The paper's GPS series are double-differenced carrier-phase positions against a "
        "stationary reference, 0.6 s, ~130 registrations per strip. Here: navtrack's own "
        "relative positioning (`navtrack.gnss.relative.solve_relative`, what `navtrack rtk` "
        "runs), kinematic mode, forward and backward combined, once with integer fixing "
        "(*fixed*: fixed where validated, float elsewhere) and once float only; local east / "
        "north / up about the mean (the paper's X / Y / Z are earth-fixed: at its site near "
        "52° N, 5° E, Y is nearly east, X and Z mix north and up). Each strip and coordinate: "
        "order by BIC (p = 0..6, d = 1..2) with the exact-likelihood estimator, then the "
        "paper's estimator at that order with both VCE forms; robust Danish weights on the "
        f"observations, process equations (3) {rp}.",
        "",
        "| series | data | Δt (s) | epochs (solved) | RTK statuses | strips (epochs) | "
        "base position |",
        "|---|---|---|---|---|---|---|",
    ]
    seen: set[str] = set()
    for row in rows:
        if row["source"] in seen:
            continue
        seen.add(row["source"])
        meta = row["meta"]
        mine = sorted({(r["strip"], r["n"]) for r in rows if r["source"] == row["source"]})
        lines.append(
            f"| {row['source']} | {meta['description']} | {row['dt_s']:g} | {meta['epochs']} "
            f"({meta['solved']}) | "
            + ", ".join(f"{k} {v}" for k, v in meta["rtk_status"].items())
            + " | "
            + ", ".join(f"{k}: {n}" for k, n in mine)
            + f" | {meta['base_source']} |"
        )
    if skipped:
        lines += ["", "Skipped: " + "; ".join(skipped)]
    return lines


def _carrier_table1(strips: dict[tuple[str, int], dict[str, dict[str, Any]]]) -> list[str]:
    """Table 1: sigma_n per strip, the printed values first."""
    lines = [
        "",
        "### Table 1: σn per strip (m), e / n / u",
        "",
        "| series | strip | σn exact | σn paper, redundancy VCE | σn paper, Förstner VCE |",
        "|---|---|---|---|---|",
    ]
    for group, vals in PAPER_TABLE2.items():
        lines.append(
            f"| paper, rms of {group} (printed, X / Y / Z) | – | – | "
            + " / ".join(f"{v:.3f}" for v in vals["ari"])
            + " | – |"
        )
    per_strip = " ".join(
        f"{c} " + " ".join(f"{v:.3f}" for v in vals) for c, vals in PAPER_TABLE1.items()
    )
    lines.append(f"| paper, strips 1,3,4,5,6,7 (printed) | – | – | {per_strip} | – |")
    for (src, strip), cols in strips.items():
        lines.append(
            f"| {src} | {strip} | "
            + " | ".join(_cells(cols, fit, "sigma_n") for fit, _ in _FITS_F)
            + " |"
        )
    return lines


def _carrier_table2(strips: dict[tuple[str, int], dict[str, dict[str, Any]]]) -> list[str]:
    """Table 2: ARI sigma_n against the least-squares accuracy."""
    lines = [
        "",
        "### Table 2: ARI σn against the least-squares accuracy",
        "",
        "Paper: σn of Table 1 over the accuracy of the positions from the adjustment with an "
        "assumed σ0 = 0.006 m (Table 2). Here: σn over the RMS of the solution's own formal "
        "single-epoch sd over the strip (navtrack RTK: 3 mm + 3 mm / sin el per undifferenced "
        "phase). Cells e / n / u.",
        "",
        "| series | strip | LS sd rms (m) | exact / LS | paper Förstner / LS |",
        "|---|---|---|---|---|",
    ]
    for group, vals in PAPER_TABLE2.items():
        lines.append(
            f"| paper, {group} (printed, X / Y / Z) | – | "
            + " / ".join(f"{v:.3f}" for v in vals["ls"])
            + " | – | "
            + " / ".join(f"{a / b:.2f}" for a, b in zip(vals["ari"], vals["ls"], strict=True))
            + " |"
        )
    for (src, strip), cols in strips.items():

        def ratio(fit: str, cols: dict[str, dict[str, Any]] = cols) -> str:
            out = []
            for c in _COLS:
                r = cols.get(c, {})
                sig = (r.get(fit) or {}).get("sigma_n")
                out.append(fmt(sig / r["ls_sd_rms"], 2) if sig is not None and r else "–")
            return " / ".join(out)

        lines.append(
            f"| {src} | {strip} | "
            + " / ".join(fmt(cols.get(c, {}).get("ls_sd_rms"), 3) for c in _COLS)
            + f" | {ratio('exact')} | {ratio('paper_forstner')} |"
        )
    return lines


def _carrier_table3(strips: dict[tuple[str, int], dict[str, dict[str, Any]]]) -> list[str]:
    """Table 3: sigma_x and r(1..3) of the filtered series."""
    lines = [
        "",
        "### Table 3: σx (m) and r(1..3) of the filtered series",
        "",
        "| series | strip | column | σx exact | r(1..3) exact | σx paper, Förstner | "
        "r(1..3) paper, Förstner |",
        "|---|---|---|---|---|---|---|",
    ]
    for k, col in enumerate(_GPS["columns"]):
        lines.append(
            f"| paper (printed, strips 3,4,5 / 1,6,7) | – | {col} | "
            f"{_GPS['sigma_x'][k]} / {_GPS['sigma_x_167'][k]} | "
            + " ".join(f"{v:.2f}" for v in _GPS["r"][k])
            + " | – | – |"
        )
    for (src, strip), cols in strips.items():
        for c in _COLS:
            r = cols.get(c)
            if r is None:
                continue
            ex, pf = r["exact"], r.get("paper_forstner") or {}
            lines.append(
                f"| {src} | {strip} | {c} | {fmt(ex['sigma_x'], 3)} | "
                + " ".join(fmt(v, 2) for v in ex["r"])
                + f" | {fmt(pf.get('sigma_x'), 3)} | "
                + (" ".join(fmt(v, 2) for v in pf.get("r", [])) or "–")
                + " |"
            )
    return lines


def _carrier_order_lines(rows: list[dict[str, Any]]) -> list[str]:
    """The orders BIC chose, against the paper's ARI(5,2)."""
    n_52 = sum(1 for r in rows if r["exact"]["order"] == [5, 2])
    orders: dict[str, int] = {}
    for r in rows:
        orders[_order(r["exact"])] = orders.get(_order(r["exact"]), 0) + 1
    lines = [
        "",
        "### The order: does the paper's ARI(5,2) come out of phase data?",
        "",
        f"BIC chose (5,2) in {n_52} of {len(rows)} strip columns; chosen orders: "
        + ", ".join(f"{k} ×{v}" for k, v in sorted(orders.items(), key=lambda kv: -kv[1]))
        + ". BIC = −2 logL + (p + 2) ln n_eff of the likelihood conditional on the first 8 "
        "epochs; *BIC(5,2) − best* > 0 means the data prefer the chosen order.",
        "",
        "| series | strip | column | chosen | BIC(5,2) − best | next orders (ΔBIC) | status | "
        "flagged | process eqs. down-weighted |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ex = r["exact"]
        lines.append(
            f"| {r['source']} | {r['strip']} | {r['column']} | {_order(ex)} | "
            f"{fmt(r['bic_52_minus_best'], 3)} | "
            + ", ".join(f"({p},{d}) {s:.1f}" for p, d, s in r["bic_top"][1:])
            + f" | {ex['status']} | {ex['n_flagged']} | {ex['n_process_downweighted']} |"
        )
    return lines


def _vce_lines(rows: Sequence[dict[str, Any]], unit_of: dict[str, str]) -> list[str]:
    """Both VCE forms of the paper's estimator side by side on the same series and order."""
    if not rows:
        return []
    lines = [
        "",
        "## Variance components: redundancy numbers against Förstner's frequency domain",
        "",
        "The paper's estimator at the same order on the same series, with its VCE step "
        "`σk² = Ωk / rk` in two forms: *redundancy* (rk = nk − tr(N⁻¹Nk), exact traces) and "
        "*Förstner* (rk the frequency-domain split of the total redundancy, "
        "`navtrack.smoothing.vce`, the paper's §2.2 recommendation). Differences are the "
        "finite-series edge effects the frequency domain leaves out.",
        "",
        "| series | column | order | σn redundancy | σn Förstner | σe redundancy | "
        "σe Förstner | rn redundancy | rn Förstner | status |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        a, b = r.get("paper_redundancy"), r.get("paper_forstner")
        if not a or not b:
            continue
        u = unit_of.get(r["source"], "")
        label = r["source"] + (f" strip {r['strip']}" if "strip" in r else "")
        lines.append(
            f"| {label} | {r['column']} | {_order(a)} | {fmt(a['sigma_n'])} {u} | "
            f"{fmt(b['sigma_n'])} {u} | {fmt(a['sigma_e'])} {u} | {fmt(b['sigma_e'])} {u} | "
            f"{fmt(a['redundancy_n'], 3)} | {fmt(b['redundancy_n'], 3)} | "
            f"{a['status']} / {b['status']} |"
        )
    return lines


def _truth_lines(truths: Sequence[dict[str, Any]]) -> list[str]:
    if not truths:
        return []
    n_match = sum(1 for t in truths if t["matched"])
    lines = [
        "",
        "## A truth for every printed column",
        "",
        "For each column the paper prints, the AR part (and σe where not printed) of the "
        "printed order fitted so that the theoretical σx/σn and r(h) of the filtered series "
        "equal the printed ones (`navtrack.experiments.ari.truths.printed_truths`: least "
        "squares over partial autocorrelations bounded to ±0.95, i.e. stationary, from zero "
        "and six random starts, best kept). *matched*: every r(h) within 0.05 of the printed "
        "value and σx/σn within 0.05 of the range its rounded printed σx and σn allow "
        f"({n_match} of {len(truths)} columns). *max dev* is the largest deviation, *worst* "
        "the statistic it belongs to. An unmatched column is one for which no stationary "
        "ARI of the printed order was found from seven starts: its printed σx/σn, σe/σn and "
        "r(h) are not jointly those of such a model as far as the search reaches; *worst* "
        "says which printed statistic the closest model cannot reproduce.",
        "",
        "| table | column | order | n | σn | σe printed | σe truth | σx/σn printed (range) | "
        "σx/σn truth | r printed | r truth | max dev | worst | matched |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in truths:
        lines.append(
            f"| {t['table']} | {t['column']} | ({t['order'][0]},{t['order'][1]}) | {t['n']} | "
            f"{t['sigma_n']} | {fmt(t['sigma_e'])} | {fmt(t['sigma_e_truth'], 3)} | "
            f"{t['ratio']:.3f} ({t['ratio_range'][0]:.3f}–{t['ratio_range'][1]:.3f}) | "
            f"{t['ratio_truth']:.3f} | "
            + " ".join(f"{v:.2f}" for v in t["r"])
            + " | "
            + " ".join(f"{v:.2f}" for v in t["r_truth"])
            + f" | {t['max_deviation']:.3f} | {t['worst']} | {fmt(t['matched'])} |"
        )
    return lines


def _ins_lines(results: dict[str, Any]) -> list[str]:
    ins = results.get("ins")
    if not ins:
        why = results.get("ins_skipped") or "switched off"
        return ["", f"## Paper Tables 4–5 on a navigation-grade INS: not run ({why})"]
    lines = [
        "",
        "## Paper Tables 4–5 in the paper's regime: a navigation-grade INS",
        "",
        ins["description"],
        "",
        "| series | column | n | order (BIC) | σn (deg) | σe (deg) | σx (deg) | r(1..3) | "
        "σn paper, redundancy / Förstner | status | motion alone: order, σn, σe | "
        "INS error step rms |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, tab in PAPER_TABLES.items():
        if "INS" not in label:
            continue
        for k, col in enumerate(tab["columns"]):
            lines.append(
                f"| {label} (printed) | {col} | – | {label.rsplit(' ', 1)[-1]} | "
                f"{tab['sigma_n'][k]} | {tab['sigma_e'][k]} | {tab['sigma_x'][k]} | "
                + " ".join(f"{v:.2f}" for v in tab["r"][k][:3])
                + " | – | – | – | – |"
            )
    for r in ins["rows"]:
        ex, tr = r["exact"], r["truth"]
        pr, pf = r.get("paper_redundancy") or {}, r.get("paper_forstner") or {}
        lines.append(
            f"| {r['source']} | {r['column']} | {r['n']} | {_order(ex)} | "
            f"{fmt(ex['sigma_n'])} | {fmt(ex['sigma_e'])} | {fmt(ex['sigma_x'])} | "
            + " ".join(fmt(v, 2) for v in ex["r"])
            + f" | {fmt(pr.get('sigma_n'))} / {fmt(pf.get('sigma_n'))} | {ex['status']} | "
            f"{_order(tr)}, {fmt(tr['sigma_n'])}, {fmt(tr['sigma_e'])} | "
            f"{fmt(r['error_step_rms_deg'])} |"
        )
    return lines


def regime_lines(results: dict[str, Any]) -> list[str]:
    """Markdown lines of the paper's-regime part of ``tables.md``."""
    lines = _carrier_lines(results)
    lines += _ins_lines(results)
    unit_of = {r["source"]: "m" for r in results.get("carrier") or []}
    ins = results.get("ins") or {}
    unit_of |= {r["source"]: "deg" for r in ins.get("rows", [])}
    lines += _vce_lines([*(results.get("carrier") or []), *ins.get("rows", [])], unit_of)
    lines += _truth_lines(results.get("printed_truths") or [])
    return lines
