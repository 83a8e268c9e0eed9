"""Check that the built documentation renders: screenshots, images and internal links.

Run after building the docs
(``python -m sphinx -W --keep-going -b html docs docs/_build/html``)::

    python scripts/check_docs_render.py [--html docs/_build/html] [--out docs/_build/screenshots]

For the index, one user-guide page and one gallery page (or the pages given
with ``--page``) it

1. parses the HTML and checks that every ``<img src>``, every local
   ``<a href>`` (including its ``#fragment``), every stylesheet
   ``<link href>`` and every local ``<script src>`` resolves to an existing
   file (and anchor) of the build;
2. opens the page in headless Chromium (Debian's ``chromium``; install it
   with ``apt-get install -y chromium``) and saves a 1280 x 2000 screenshot;
   a screenshot that is almost uniformly one colour counts as a failure.

It exits with 1 if any check fails and with 2 if Chromium cannot be found
(``--no-screenshots`` skips step 2).  Look at the screenshots: the theme's
navigation bar, the sidebars and the figures should all be visible.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_PAGES = ("index.html", "user_guide/data.html", "auto_examples/plot_quick_start.html")
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--virtual-time-budget=15000",  # let scripts (search, MathJax) finish before the capture
    "--window-size=1280,2000",
)


class _References(HTMLParser):
    """Collects what a page refers to, and the ids it defines."""

    def __init__(self):
        super().__init__()
        self.references = []  # (kind, url)
        self.ids = set()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for key in ("id", "name"):
            if attrs.get(key):
                self.ids.add(attrs[key])
        if tag == "img" and "src" in attrs:
            self.references.append(("img", attrs["src"] or ""))
        elif tag == "a" and attrs.get("href"):
            self.references.append(("a", attrs["href"]))
        elif tag == "link" and "stylesheet" in (attrs.get("rel") or "").split() and attrs.get("href"):
            self.references.append(("stylesheet", attrs["href"]))
        elif tag == "script" and attrs.get("src"):
            self.references.append(("script", attrs["src"]))


def _parse(path: Path) -> _References:
    parser = _References()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def check_references(page: Path, html_root: Path, cache: dict) -> list[str]:
    """Problems with the local images, links, stylesheets and scripts of one page."""
    problems = []
    parsed = _parse(page)
    n_images = 0
    for kind, url in parsed.references:
        parts = urlsplit(url)
        if parts.scheme or parts.netloc:  # http(s), mailto, data:, javascript: ...
            continue
        if kind == "img":
            n_images += 1
        target = (page.parent / unquote(parts.path)).resolve() if parts.path else page.resolve()
        if target.is_dir():
            target = target / "index.html"
        if not target.is_file():
            problems.append(f"{page.relative_to(html_root)}: <{kind}> {url!r} -> missing {target}")
            continue
        if kind == "a" and parts.fragment and target.suffix == ".html":
            if target not in cache:
                cache[target] = _parse(target).ids
            if unquote(parts.fragment) not in cache[target]:
                problems.append(f"{page.relative_to(html_root)}: <a> {url!r} -> no anchor #{parts.fragment}")
    stylesheets = [url for kind, url in parsed.references if kind == "stylesheet"]
    if not any("pydata-sphinx-theme" in url or "styles/theme" in url for url in stylesheets):
        problems.append(f"{page.relative_to(html_root)}: the PyData theme's stylesheet is not linked")
    return problems, n_images


def find_chromium() -> str | None:
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


def screenshot(chromium: str, page: Path, png: Path) -> str | None:
    """Save a screenshot of ``page``; return a problem description or None."""
    with tempfile.TemporaryDirectory(prefix="chromium-profile-") as profile:
        command = [
            chromium,
            *CHROMIUM_FLAGS,
            f"--user-data-dir={profile}",
            f"--screenshot={png}",
            page.resolve().as_uri(),
        ]
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=120)
        except subprocess.TimeoutExpired:
            return f"{page.name}: Chromium timed out"
    if not png.is_file() or png.stat().st_size == 0:
        return f"{page.name}: no screenshot (Chromium exit {result.returncode}: {result.stderr.strip()[-500:]})"
    try:
        from PIL import Image
    except ImportError:  # pillow comes with matplotlib; without it, skip the blank-page test
        return None
    with Image.open(png) as image:
        grey = image.convert("L").resize((128, 200))
        histogram = grey.histogram()
    if max(histogram) > 0.995 * sum(histogram):
        return f"{page.name}: the screenshot is blank (one colour)"
    return None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--html", type=Path, default=ROOT / "docs" / "_build" / "html", help="built HTML folder")
    parser.add_argument("--out", type=Path, default=None, help="screenshot folder (default: <html>/../screenshots)")
    parser.add_argument("--page", action="append", default=None, help="page relative to --html (repeatable)")
    parser.add_argument("--no-screenshots", action="store_true", help="only check images and links")
    args = parser.parse_args(argv)

    html_root = args.html.resolve()
    pages = args.page or list(DEFAULT_PAGES)
    out = (args.out or html_root.parent / "screenshots").resolve()
    problems = []
    cache = {}
    for name in pages:
        page = html_root / name
        if not page.is_file():
            problems.append(f"{name}: page not built ({page})")
            continue
        found, n_images = check_references(page, html_root, cache)
        problems += found
        print(f"{name}: {n_images} images, {len(found)} problems")

    if not args.no_screenshots:
        chromium = find_chromium()
        if chromium is None:
            print("Chromium not found (apt-get install -y chromium), or pass --no-screenshots", file=sys.stderr)
            return 2
        out.mkdir(parents=True, exist_ok=True)
        for name in pages:
            page = html_root / name
            if not page.is_file():
                continue
            png = out / (name.replace("/", "__").removesuffix(".html") + ".png")
            problem = screenshot(chromium, page, png)
            if problem:
                problems.append(problem)
            else:
                print(f"screenshot: {png}")

    for problem in problems:
        print("PROBLEM:", problem, file=sys.stderr)
    print("OK" if not problems else f"{len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
