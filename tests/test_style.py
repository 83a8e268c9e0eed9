"""The code style is a test: ruff's linter and formatter (configured in pyproject.toml) pass on the whole tree.

ruff is in the test extra, so a missing ruff fails here instead of skipping.
"""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("command", [["check"], ["format", "--check"]], ids=["lint", "format"])
def test_ruff_passes(command):
    result = subprocess.run(
        [sys.executable, "-m", "ruff", *command, "."], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_gallery_code_fits_the_documentation_column():
    # examples/ruff.toml wraps the gallery's code at 88 characters, the width of a code block in the docs'
    # page column; a string the formatter cannot split would still scroll sideways, so every code line is checked.
    too_long = [
        f"{path.name}:{number}"
        for path in sorted((ROOT / "examples").glob("*.py"))
        for number, line in enumerate(path.read_text().splitlines(), start=1)
        if len(line) > 88 and not line.lstrip().startswith("#")
    ]
    assert not too_long, too_long
