"""The positioning pipeline: the same positions as the SPP chain it runs, and the layering it
stands on (``gnss`` knows nothing of ``integrity``; neither knows the pipeline above them)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

import navtrack
from navtrack.data import sample_path
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, SppResult, solution_frame, solve_spp
from navtrack.positioning import PositionSolution, solve_positions
from navtrack.positioning import solution_frame as pipeline_frame

ROOT = Path(navtrack.__file__).parent

# package -> packages it must not import (at module level or inside functions)
FORBIDDEN = {
    "estimation": ("gnss", "integrity", "positioning", "experiments", "cli", "tracking"),
    "gnss": ("integrity", "positioning", "experiments", "cli"),
    "integrity": ("positioning", "experiments", "cli"),
    "positioning": ("experiments", "cli"),
}


def _imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_layers_import_only_downward() -> None:
    bad = []
    for package, above in FORBIDDEN.items():
        for path in sorted((ROOT / package).rglob("*.py")):
            for module in _imports(path):
                parts = module.split(".")
                if parts[0] == "navtrack" and len(parts) > 1 and parts[1] in above:
                    bad.append(f"{path.relative_to(ROOT)} imports {module}")
    assert not bad, "\n".join(bad)


def test_pipeline_without_raim_is_the_spp_chain() -> None:
    obs = read_obs(sample_path("SEPT078M_120.21O"))
    nav = read_nav(sample_path("SEPT078M.21P"))
    cfg = SppConfig(systems="GE")
    spp = solve_spp(obs, [nav], config=cfg, chunk_epochs=50)
    sol = solve_positions(obs, [nav], config=cfg, chunk_epochs=50)
    assert isinstance(sol, PositionSolution)
    assert isinstance(sol, SppResult)
    assert sol.integrity is None
    np.testing.assert_array_equal(sol.pos_m, spp.pos_m)
    np.testing.assert_array_equal(sol.status, spp.status)
    np.testing.assert_array_equal(sol.isb_m, spp.isb_m)
    a, b = pipeline_frame(sol), solution_frame(spp)
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
