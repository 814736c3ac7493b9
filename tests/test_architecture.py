"""The import graph between navtrack's packages obeys the layering table of docs/architecture.md.

The table (section "What may import what") is parsed from the page, and every import of a
navtrack module in ``src/navtrack`` -- at module level or inside a function -- is checked
against it. A failure lists each offending edge with the modules that make it.
"""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "navtrack"
DOC = ROOT / "docs" / "architecture.md"

#: The heading of the layering table in docs/architecture.md.
TABLE_HEADING = "## What may import what"

#: Name of the layer of the modules directly under ``navtrack/`` (geodesy, timescale, ...).
BASE = "navtrack"

#: Packages that belong to :data:`BASE` (the bundled sample files).
BASE_PACKAGES = frozenset({"data"})


def layering_table(text: str) -> dict[str, set[str]]:
    """``package -> packages it may import`` from the Markdown table under
    :data:`TABLE_HEADING`: rows ``| `package` | owns | `a`, `b` |`` (``—`` for none)."""
    section = text.split(TABLE_HEADING, 1)[1].split("\n## ", 1)[0]
    rows = [ln for ln in section.splitlines() if ln.startswith("|")]
    allowed: dict[str, set[str]] = {}
    for row in rows[2:]:  # header and separator
        cells = [c.strip() for c in row.strip().strip("|").split("|")]
        package = re.findall(r"`([\w.]+)`", cells[0])
        if len(package) != 1 or len(cells) < 3:
            raise ValueError(f"docs/architecture.md: cannot read the layering row {row!r}")
        allowed[package[0]] = set(re.findall(r"`([\w.]+)`", cells[-1]))
    return allowed


def _module_name(path: Path, src: Path) -> str:
    parts = list(path.relative_to(src.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


#: Modules directly under ``navtrack`` that are layers of their own (a module rather than a
#: package may hold one, as the positioning pipeline may).
MODULE_LAYERS = frozenset({"positioning"})


def layer_of(module: str, src: Path = SRC) -> str:
    """The layer of a module: its package under ``navtrack`` (``navtrack.gnss.spp`` ->
    ``gnss``); modules directly under ``navtrack`` are :data:`BASE`, except those of
    :data:`MODULE_LAYERS` and ``__main__``, the command line's entry point."""
    parts = module.split(".")
    if len(parts) == 1:
        return BASE
    if parts[1] == "__main__":
        return "cli"
    if parts[1] in BASE_PACKAGES:
        return BASE
    if parts[1] in MODULE_LAYERS or (src / parts[1]).is_dir():
        return parts[1]
    return BASE


def import_edges(src: Path = SRC) -> dict[tuple[str, str], set[str]]:
    """``(importing layer, imported layer) -> importing modules`` over every import of a
    navtrack module under ``src``, wherever it sits (module level, functions,
    ``TYPE_CHECKING`` blocks)."""
    edges: dict[tuple[str, str], set[str]] = defaultdict(set)
    for path in sorted(src.rglob("*.py")):
        module = _module_name(path, src)
        package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target == "navtrack":  # from navtrack import geodesy, __version__, ...
                    targets = [f"navtrack.{alias.name}" for alias in node.names]
                elif target.startswith("navtrack."):
                    targets = [target]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.split(".")[0] == "navtrack"]
            for target in targets:
                edge = (layer_of(module, src), layer_of(target, src))
                if edge[0] != edge[1]:
                    edges[edge].add(module)
    return edges


def test_the_table_names_every_package() -> None:
    allowed = layering_table(DOC.read_text(encoding="utf-8"))
    packages = {
        p.name for p in SRC.iterdir() if p.is_dir() and (p / "__init__.py").exists()
    } - BASE_PACKAGES
    assert packages | {BASE} <= set(allowed), (
        f"packages missing from the table in {DOC.name}: {sorted(packages | {BASE} - set(allowed))}"
    )
    unknown = {dep for deps in allowed.values() for dep in deps} - set(allowed)
    assert not unknown, f"the table allows imports of unknown packages: {sorted(unknown)}"


def test_the_layering_has_no_cycle() -> None:
    """What the table allows is itself a tree of layers: no package may import one that may
    import it back."""
    allowed = layering_table(DOC.read_text(encoding="utf-8"))
    cycles = sorted((a, b) for a, deps in allowed.items() for b in deps if a in allowed.get(b, ()))
    assert not cycles, f"the table allows both directions of {cycles}"


def test_imports_obey_the_table() -> None:
    allowed = layering_table(DOC.read_text(encoding="utf-8"))
    offending = {
        (a, b): modules
        for (a, b), modules in import_edges().items()
        if a in allowed and b not in allowed[a]
    }
    if offending:
        report = "\n".join(
            f"  {a} -> {b}: {', '.join(sorted(modules))}"
            for (a, b), modules in sorted(offending.items())
        )
        pytest.fail(f"imports the table in docs/architecture.md does not allow:\n{report}")


def test_the_checker_sees_imports_inside_functions(tmp_path: Path) -> None:
    """A function-level or relative import is an edge like a module-level one; imports inside
    a package and of the base modules are not edges between packages."""
    src = tmp_path / "navtrack"
    for folder in ("gnss", "experiments"):
        (src / folder).mkdir(parents=True)
        (src / folder / "__init__.py").write_text("")
    (src / "__init__.py").write_text("")
    (src / "geodesy.py").write_text("")
    (src / "gnss" / "network.py").write_text(
        "from navtrack import geodesy\nfrom . import spp\n\n"
        "def run():\n    from navtrack.experiments.runner import run_monte_carlo\n"
    )
    (src / "experiments" / "runner.py").write_text("from ..gnss import network\n")
    edges = import_edges(src)
    assert dict(edges) == {
        ("gnss", "experiments"): {"navtrack.gnss.network"},
        ("gnss", BASE): {"navtrack.gnss.network"},
        ("experiments", "gnss"): {"navtrack.experiments.runner"},
    }
    assert layer_of("navtrack.__main__", src) == "cli"
    assert layer_of("navtrack.positioning", src) == "positioning"
    assert layer_of("navtrack.data", src) == BASE
