"""``navtrack smooth`` input: bad values and times named by file line (issue 9, failures 5-6)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import navtrack.smoothing.fitting
from navtrack.cli import EXIT_BAD_INPUT, main
from navtrack.smoothing.ari import AriConfig, AriStatus, fit_ari, simulate_ari

# A comment line, the header, then 60 rows: row k is on file line k + 3.
_LINES = ["# smoothing input", "t_s,v_m"] + [
    f"{k},{np.sin(k / 5) + 0.01 * k:.6f}" for k in range(60)
]


def _file(tmp_path: Path, line: int, text: str, replace: bool = True) -> Path:
    rows = list(_LINES)
    if replace:
        rows[line - 1] = text
    else:
        rows.insert(line - 1, text)
    path = tmp_path / "series.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize(
    ("line", "text", "replace", "message"),
    [
        (21, "18,inf", True, "column 'v_m': infinite value"),
        (22, "19,1e400", True, "column 'v_m': infinite value"),
        (23, "hello world", True, "column 't_s': 'hello world' is not a number"),
        (24, "t_s,v_m", False, "column 'v_m': 'v_m' is not a number (the header line repeated)"),
        (25, "21,0.5", True, "time 21 s repeats 21 s of line 24"),
        (26, "3,0.5", True, "time 3 s goes back from 22 s of line 25"),
        (27, ",0.5", True, "time column 't_s': no time stamp"),
    ],
)
def test_bad_values_and_times_name_the_file_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    line: int,
    text: str,
    replace: bool,
    message: str,
) -> None:
    path = _file(tmp_path, line, text, replace)
    assert main(["smooth", str(path)]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith(f"navtrack smooth: error: {path}:{line}: {message}"), err
    assert "Traceback" not in err


def test_empty_value_is_a_missing_epoch(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _file(tmp_path, 30, "27,")
    assert main(["smooth", str(path), "--order", "1,1"]) == 0
    assert "(missing 1)" in capsys.readouterr().out


def test_singular_system_is_a_status(monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 9, failure 5: a LinAlgError inside the estimation escaped fit_ari. The estimator is
    # made to meet a singular system; the fit reports it as a status of the series.
    def singular(*_: object, **__: object) -> None:
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(navtrack.smoothing.fitting, "estimate_exact_likelihood", singular)
    y, _ = simulate_ari(np.random.default_rng(3), 80, [-0.4], 1, 0.02, 0.01)
    y[17] = np.nan
    res = fit_ari(y, AriConfig(order=(1, 1)))
    assert res.status == AriStatus.SINGULAR
    assert "Singular matrix" in res.message
    assert np.isnan(res.x).all()


def test_last_row_cut_mid_line_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 9, failure 10 for tables: "59,0.9" cut to "59," read the row as a missing value
    path = tmp_path / "cut.csv"
    path.write_text("\n".join(_LINES)[: -len(_LINES[-1]) + 2])  # no end of line
    assert main(["smooth", str(path)]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith(f"navtrack smooth: error: {path}:{len(_LINES)}: last row cut short")
    # all fields but no end of line: a value may be cut short ("0.91" -> "0.9"); reported
    whole = tmp_path / "whole.csv"
    whole.write_text("\n".join(_LINES))
    assert main(["smooth", str(whole), "--order", "1,1"]) == EXIT_BAD_INPUT
    assert "no end of line" in capsys.readouterr().err
    whole.write_text("\n".join(_LINES) + "\n")
    assert main(["smooth", str(whole), "--order", "1,1"]) == 0
