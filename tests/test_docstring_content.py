"""Docstrings say what and in which units; history, dates and measured results live in the user guide.

Every module, class and function docstring in ``sklearn_radar/`` (read with :mod:`ast`, so nothing is
imported) is searched, line by line, for three kinds of content that belong in ``docs/user_guide/*.rst`` or
``docs/performance.rst`` instead:

* issue references: ``issue 27``, ``issue #27``, ``(#27)``, ``session 14``, ``PR 12``, ``gh-12``.  The
  paper's experiments are written ``#1`` .. ``#13`` and are legitimate, so a bare ``#N`` counts only for
  ``N`` above 13;
* dates: ``2026-11-01``, ``Nov 2026``, ``1 November 2026``, ``as of 2026``.  Publication years in
  citations (``Scheiner et al. (2019)``, ``Liu et al. 2022``, ``CVPR 2019``) carry no month and pass;
* measured results: pointers to ``benchmarks/`` scripts, ``measured`` as a source (``(measured)``,
  ``measured:``, ``measured on ...``), timings of this code (``took 31.6 s``, ``0.05 s per million``,
  ``0.3 ms of CPU``), speed ratios (``5-8x faster``, ``2.1x slower``), load averages and machine sizes
  (``on a 2-core machine``).

Units in parameter descriptions (``in s``, ``m/s``, ``500 ms``), default values, equation, table and figure
numbers pass, as do ``#:`` attribute comments (they are not docstrings).  A line that matches but is
legitimate goes into :data:`ALLOWED` with its reason.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "sklearn_radar"

#: The highest experiment number of the paper (Tables III and IV: #1-#13); a higher ``#N`` is an issue.
LAST_EXPERIMENT = 13

_MONTH = r"(?:jan|feb|mar|apr|may|jun|jul|aug|sep|sept|oct|nov|dec)[a-z]*\.?"
_TIME_UNIT = r"(?:s|ms|µs|us|ns|sec|secs|seconds?|min|mins|minutes?|h|hours?)\b"
_NUMBER = r"\d+(?:[.,]\d+)?(?:\s*(?:-|/|to)\s*\d+(?:[.,]\d+)?)?"

#: (kind, pattern) pairs; each pattern is searched case-insensitively in each docstring line.
PATTERNS = [
    ("issue reference", re.compile(r"\bissues?\s+#?\d+", re.I)),
    ("issue reference", re.compile(r"\bsessions?\s+#?\d+", re.I)),
    ("issue reference", re.compile(r"\b(?:PR|pull request)\s*#?\d+|\bgh-\d+", re.I)),
    ("date", re.compile(r"\b(?:19|20)\d\d-[01]\d-[0-3]\d\b")),
    ("date", re.compile(rf"\b{_MONTH}\s+(?:19|20)\d\d\b", re.I)),
    ("date", re.compile(rf"\b[0-3]?\d\s+{_MONTH}\s+(?:19|20)\d\d\b", re.I)),
    ("date", re.compile(r"\b(?:as of|since|until|by)\s+(?:19|20)\d\d\b", re.I)),
    ("measured result", re.compile(r"\bbenchmarks/|\bbench_\w+\.py|\bexperiment_\w+\.py", re.I)),
    (
        "measured result",
        re.compile(
            r"\(measured[):;]|,\s*measured[:)]|\bmeasured\s+in\s+``"
            r"|\bmeasured\s+on\s+(?:simulated|real|the default|an?\s|\d)",
            re.I,
        ),
    ),
    (
        "measured result",
        re.compile(
            rf"\b(?:took|takes|ran in|runs in|loads?\b.{{0,20}}\bin|dumps?\b.{{0,20}}\bin)\s+(?:about\s+)?"
            rf"{_NUMBER}\s*{_TIME_UNIT}",
            re.I,
        ),
    ),
    ("measured result", re.compile(rf"{_NUMBER}\s*{_TIME_UNIT}\s+(?:of CPU|per million|per \d)", re.I)),
    (
        "measured result",
        re.compile(r"\b\d+(?:\.\d+)?(?:\s*-\s*\d+(?:\.\d+)?)?\s*[x×]\s+(?:faster|slower|less|more)\b", re.I),
    ),
    ("measured result", re.compile(r"\b\d+(?:\.\d+)?(?:-\d+(?:\.\d+)?)?[x×](?!\w)", re.I)),
    ("measured result", re.compile(r"\b\d+(?:\.\d+)?\s+times\s+(?:faster|slower)\b", re.I)),
    ("measured result", re.compile(r"\b(?:twice|half|three times|four times) as (?:fast|slow)\b", re.I)),
    ("measured result", re.compile(r"\bload average|\bload\s+(?:of\s+)?\d", re.I)),
    ("measured result", re.compile(r"\b\d+-(?:core|cpu)\b|\bon\s+(?:a|one|an?)\s+\d+\s+cores?\b", re.I)),
]

#: ``(path relative to sklearn_radar/, stripped line): reason`` for lines that match a pattern but are legitimate.
ALLOWED: dict[tuple[str, str], str] = {}


def _issue_numbers(line):
    """``#N`` numbers above the paper's last experiment: issue or pull-request numbers."""
    return [m.group(0) for m in re.finditer(r"(?<![\w&])#(\d+)\b", line) if int(m.group(1)) > LAST_EXPERIMENT]


def _docstrings(path):
    """``(first line number, text)`` of the module's, each class's and each function's docstring."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                if isinstance(first.value.value, str):
                    yield first.value.lineno, first.value.value


def _findings():
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE).as_posix()
        for start, text in _docstrings(path):
            for offset, line in enumerate(text.splitlines()):
                stripped = line.strip()
                if (relative, stripped) in ALLOWED:
                    continue
                hits = [(kind, m.group(0)) for kind, pattern in PATTERNS for m in pattern.finditer(line)]
                hits += [("issue reference", number) for number in _issue_numbers(line)]
                for kind, match in hits:
                    yield f"sklearn_radar/{relative}:{start + offset}: {kind} {match!r} in: {stripped}"


def test_docstrings_hold_no_issue_references_dates_or_measured_results():
    findings = list(_findings())
    assert not findings, (
        "Move these to docs/user_guide/*.rst or docs/performance.rst and link the page "
        "(':ref:`User Guide <user-guide-...>`'):\n" + "\n".join(findings)
    )


def test_allowed_entries_still_match():
    # An entry whose line was rewritten or no longer matches would silently allow a future line.
    lines = {
        (path.relative_to(PACKAGE).as_posix(), line.strip())
        for path in PACKAGE.rglob("*.py")
        for _, text in _docstrings(path)
        for line in text.splitlines()
    }
    stale = [key for key in ALLOWED if key not in lines]
    assert not stale, stale


def test_patterns_catch_what_they_are_for():
    # The patterns themselves, on one example of each kind and on legitimate content.
    def flagged(line):
        return bool(_issue_numbers(line)) or any(pattern.search(line) for _, pattern in PATTERNS)

    offending = [
        "The converter (issue 28) loads faster.",
        "See issue #27.",
        "Added in (#27).",
        "As decided in session 14.",
        "Changed on 2026-11-01.",
        "Measured in Nov 2026.",
        "about 0.05 s per million detections",
        "5-8x faster than the loop",
        "the whole run took 31.6 s",
        "measured on simulated data, two seeds",
        "(``benchmarks/bench_classifier.py --profile``)",
        "at a load average of 3",
        "on a 2-core machine",
        "2.1x slower per detection",
        "A compiled loop: twice as fast as the numpy block.",
    ]
    legitimate = [
        "Time window of Eq. 5, in s.",
        "Velocity threshold, m/s (the paper's #12: 23.11 deg).",
        "The paper's experiments #1-#13 (Table III, Fig. 6).",
        "Length of a time window in s, > 0 (Scheiner et al. 2021: 500 ms);",
        "Scheiner et al. (2019), Liu et al. 2022, CVPR 2019.",
        "For each occupied cell, the indices of its 3 x 3 neighbourhood.",
        "The default run's budget: 4 sequences x 20 s, 10 iterations (30 % random), 2 folds.",
        "``vr`` is the measured Doppler velocity.",
        "Homogeneity, completeness and V-measure with background handled as in Scheiner et al. 2019.",
        "joblib's ``n_jobs`` (-1: all cores).",
        "default=0.25",
    ]
    assert [line for line in offending if not flagged(line)] == []
    assert [line for line in legitimate if flagged(line)] == []
