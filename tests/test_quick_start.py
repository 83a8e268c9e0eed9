"""The quick start of the README and of the getting-started page runs and prints what the text says.

Each page's Python block is run as it stands, in a fresh interpreter; every
line it prints that ends in a number must print the number that the block's
own comment on its ``print`` line promises.
"""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _readme_block():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 1, "the README has one Python block, the quick start"
    return blocks[0]


def _getting_started_block():
    text = (ROOT / "docs" / "getting_started.rst").read_text(encoding="utf-8")
    match = re.search(r"\.\. code-block:: python\n\n((?:    .*\n|\n)+)", text)
    assert match, "docs/getting_started.rst has a Python code block"
    return textwrap.dedent(match.group(1))


def _promised(code):
    """The number in the comment of each ``print`` line, in order."""
    promised = []
    for line in code.splitlines():
        if line.lstrip().startswith("print(") and "#" in line:
            number = re.search(r"#\s*(-?\d+(?:\.\d+)?)", line)
            if number:
                promised.append(number.group(1))
    return promised


@pytest.mark.parametrize("block", [_readme_block, _getting_started_block], ids=["README", "getting_started"])
def test_quick_start_prints_what_its_comment_says(block):
    code = block()
    promised = _promised(code)
    assert promised, "the quick start promises a printed figure in a comment"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-3000:]
    printed = [re.search(r"(-?\d+(?:\.\d+)?)\s*$", line).group(1) for line in result.stdout.splitlines()]
    assert printed == promised, f"printed {printed}, the comments say {promised}"
