"""The package's layers: no core module imports the runner (``reproduce``) or the command line (``cli``)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "sklearn_radar"
UPPER = ("reproduce", "cli")


def _imported_modules(path):
    """(line, absolute module) of every import in the module at ``path``, relative ones resolved."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    package = parts[:-1]  # a module's package; an __init__'s own package (its last part is "__init__")
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *(node.module.split(".") if node.module else [])])
            names = [module] if node.module else [f"{module}.{alias.name}" for alias in node.names]
            for name in names:
                yield node.lineno, name
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name


def _layer(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == "sklearn_radar" and parts[1] in UPPER else None


def test_no_core_module_imports_the_runner_or_the_command_line():
    offending = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE)
        if relative.parts[0] in UPPER or relative.name == "__main__.py":
            continue
        offending += [
            f"{relative}:{line} imports {module}" for line, module in _imported_modules(path) if _layer(module)
        ]
    assert not offending, "\n".join(offending)


def test_the_guard_resolves_relative_imports():
    """The check above can fail: a core module's relative import of the runner is seen as one."""
    source = PACKAGE / "online" / "_replay.py"
    assert _layer("sklearn_radar.reproduce._io") == "reproduce"
    resolved = dict(_imported_modules(source)).values()
    assert "sklearn_radar._labels" in resolved  # ``from .._labels import ...`` in sklearn_radar/online


@pytest.mark.parametrize("module", ["sklearn_radar.online", "sklearn_radar.classification", "sklearn_radar"])
def test_importing_a_core_subpackage_loads_neither_the_runner_nor_the_command_line(module):
    code = (
        f"import sys, {module}; "
        "print(sorted(m for m in sys.modules if m.split('.')[:2] in (['sklearn_radar', 'reproduce'], "
        "['sklearn_radar', 'cli'])))"
    )
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "[]", loaded


def test_the_stages_import_nothing_of_the_online_package():
    # online composes the stages (it imports cluster and preprocessing), so stage 1's scan-by-scan state, which
    # RadarDBSCAN.partial_fit uses, lives in cluster/_radar_dbscan_stream.py: a stage importing online is a cycle.
    offending = []
    for stage in ("cluster", "preprocessing"):
        for path in sorted((PACKAGE / stage).rglob("*.py")):
            offending += [
                f"{path.relative_to(PACKAGE)}:{line} imports {module}"
                for line, module in _imported_modules(path)
                if module == "sklearn_radar.online" or module.startswith("sklearn_radar.online.")
            ]
    assert not offending, "\n".join(offending)
