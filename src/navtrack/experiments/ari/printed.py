"""The ARI paper's printed values (Lindenberger, Tables 1–5) and the cell format of the
reproduction's tables."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["PAPER_TABLE1", "PAPER_TABLE2", "PAPER_TABLES", "fmt"]

#: The paper's published figures (Lindenberger, Tables 1, 3, 4, 5), for the tables' context.
PAPER_TABLES: dict[str, dict[str, Any]] = {
    "GPS (Table 1 rms strips 3,4,5 / Table 3), m, 0.6 s, ARI(5,2)": {
        "sigma_n": [0.021, 0.010, 0.026],
        "sigma_x": [0.017, 0.007, 0.021],
        "r": [[0.46, -0.06, 0.06], [0.69, 0.11, -0.15], [0.52, -0.01, -0.10]],
        "columns": ["X", "Y", "Z"],
        # Table 1 rms of strips 1,6,7 and Table 3's second sigma_x row (same r(h) printed)
        "sigma_n_167": [0.018, 0.010, 0.021],
        "sigma_x_167": [0.013, 0.006, 0.016],
    },
    "Shuttle INS (Table 4), deg, 2 s, ARI(6,1)": {
        "sigma_n": [0.0060, 0.0048, 0.0060],
        "sigma_e": [0.0019, 0.0012, 0.0014],
        "sigma_x": [0.0027, 0.0027, 0.0031],
        "r": [[0.71, 0.46, 0.18, 0.13], [0.62, 0.39, 0.10, 0.13], [0.67, 0.47, 0.15, 0.13]],
        "columns": ["yaw", "pitch", "roll"],
    },
    "Aircraft INS (Table 5), deg, 10 Hz, ARI(2,2)": {
        "sigma_n": [0.0023, 0.0035, 0.0030],
        "sigma_e": [0.0005, 0.0013, 0.0026],
        "sigma_x": [0.0011, 0.0013, 0.0017],
        "r": [[0.86, 0.57, 0.29, 0.09], [0.79, 0.40, 0.09, -0.07], [0.80, 0.41, 0.08, -0.09]],
        "columns": ["yaw", "pitch", "roll"],
    },
}


def fmt(value: Any, digits: int = 4) -> str:
    """A table cell: ``–`` for none or non-finite, yes/no, 4 significant digits (``digits``)."""
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "–"
        if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e5):
            return f"{value:.{digits - 1}e}"
        return f"{value:.{digits}g}"
    return str(value)


#: Paper Tables 1 and 2: ARI ``sigma_n`` (rms of strips) and the single-epoch least-squares
#: accuracy with the assumed sigma_0 = 0.006 m, GPS X/Y/Z in m.
PAPER_TABLE2: dict[str, dict[str, list[float]]] = {
    "strips 3,4,5": {"ari": [0.021, 0.010, 0.026], "ls": [0.022, 0.009, 0.017]},
    "strips 1,6,7": {"ari": [0.018, 0.010, 0.021], "ls": [0.020, 0.009, 0.020]},
}
#: Paper Table 1: ARI ``sigma_n`` per strip (strips 1, 3, 4, 5, 6, 7), GPS X/Y/Z in m.
PAPER_TABLE1: dict[str, list[float]] = {
    "X": [0.027, 0.020, 0.024, 0.020, 0.014, 0.012],
    "Y": [0.011, 0.009, 0.009, 0.013, 0.011, 0.007],
    "Z": [0.038, 0.026, 0.027, 0.024, 0.014, 0.010],
}
