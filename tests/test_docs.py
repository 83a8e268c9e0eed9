"""The documentation builds with warnings as errors and every gallery example runs.

The build is the one of ``docs/conf.py``,
``python -m sphinx -W --keep-going -b html docs docs/_build/html``, run on a
copy of ``docs/`` and ``examples/`` in a temporary folder: the gallery is
executed afresh (no stale results of an earlier build are reused) and
nothing is written into the work tree.  A broken example, a docstring that
numpydoc or docutils cannot parse, or a broken cross-reference turns it red.

A missing documentation toolchain (``pip install -e ".[test]"`` installs it)
is a failure, not a skip, so that CI cannot pass without building the docs.
Set ``SKLEARN_RADAR_SKIP_DOCS=1`` to skip this module on purpose.
"""

from __future__ import annotations

import importlib
import os
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

if os.environ.get("SKLEARN_RADAR_SKIP_DOCS") == "1":
    pytest.skip("SKLEARN_RADAR_SKIP_DOCS=1: docs build skipped on request", allow_module_level=True)

# Plain imports: without the toolchain this module errors instead of skipping quietly.
import numpydoc  # noqa: F401
import pydata_sphinx_theme  # noqa: F401
import sphinx  # noqa: F401
import sphinx_gallery  # noqa: F401

ROOT = Path(__file__).resolve().parents[1]

#: One page of each kind whose images must all resolve.
PAGES = ("index.html", "user_guide/data.html", "auto_examples/plot_quick_start.html")

#: Modules whose ``__all__`` the API reference must cover.
PUBLIC_MODULES = (
    "sklearn_radar",
    "sklearn_radar.datasets",
    "sklearn_radar.preprocessing",
    "sklearn_radar.cluster",
    "sklearn_radar.classification",
    "sklearn_radar.metrics",
    "sklearn_radar.evaluation",
    "sklearn_radar.model_selection",
    "sklearn_radar.experiments",
    "sklearn_radar.reproduce",
    "sklearn_radar.online",
)


class _Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.sources = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.sources.append(dict(attrs).get("src") or "")


@pytest.fixture(scope="module")
def built_docs(tmp_path_factory):
    """Build a copy of docs/ and examples/; return the HTML folder."""
    work = tmp_path_factory.mktemp("docs")
    ignore = shutil.ignore_patterns(
        "_build", "auto_examples", "generated", "_generated", "sg_execution_times.rst", "__pycache__"
    )
    shutil.copytree(ROOT / "docs", work / "docs", ignore=ignore)
    shutil.copytree(ROOT / "examples", work / "examples", ignore=ignore)
    html = work / "html"
    command = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", str(work / "docs"), str(html)]
    result = subprocess.run(command, cwd=work, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, (
        f"docs build failed ({' '.join(command)}):\n{result.stdout[-5000:]}\n{result.stderr[-10000:]}"
    )
    return html


def test_docs_build_with_warnings_as_errors(built_docs):
    for page in PAGES:
        assert (built_docs / page).is_file(), f"{page} was not built"


@pytest.mark.parametrize("page", PAGES)
def test_every_image_of_a_page_exists(built_docs, page):
    parser = _Images()
    parser.feed((built_docs / page).read_text(encoding="utf-8"))
    assert parser.sources, f"{page} shows no image"
    for source in parser.sources:
        parts = urlsplit(source)
        if parts.scheme in ("http", "https", "data"):
            continue
        target = (built_docs / page).parent / unquote(parts.path)
        assert target.is_file(), f"{page}: <img src={source!r}> points to a missing file"


def test_every_gallery_example_has_a_page(built_docs):
    for example in sorted((ROOT / "examples").glob("plot_*.py")):
        assert (built_docs / "auto_examples" / f"{example.stem}.html").is_file(), example.name


def test_api_reference_covers_every_public_name(built_docs):
    top = importlib.import_module("sklearn_radar")
    missing = []
    for module_name in PUBLIC_MODULES:
        module = importlib.import_module(module_name)
        for name in module.__all__:
            if name.startswith("__"):
                continue
            obj = getattr(module, name)
            canonical = "sklearn_radar" if getattr(top, name, None) is obj else module_name
            if not (built_docs / "api" / "generated" / f"{canonical}.{name}.html").is_file():
                missing.append(f"{module_name}.{name}")
    assert not missing, f"public names without an API page (add them to docs/api.rst): {missing}"
