"""Sphinx configuration of the sklearn-radar documentation.

Build (warnings are errors, the gallery is executed)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Layout follows scikit-learn-contrib projects: ``sphinx.ext.autosummary``
with generated stub pages (``api/generated/``), ``numpydoc`` for the
docstrings, ``sphinx_gallery.gen_gallery`` for ``examples/`` (rendered into
``auto_examples/``) and the PyData theme.
"""

from __future__ import annotations

import importlib
import io
import re
import sys
from pathlib import Path

import sklearn_radar

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "sphinxext"))  # gallery_order

# -- Project -----------------------------------------------------------------

project = "sklearn-radar"
author = "the sklearn-radar developers"
copyright = "the sklearn-radar developers; method: Scheiner, Appenrodt, Dickmann and Sick (ITSC 2019)"
release = sklearn_radar.__version__
version = release

# -- General -----------------------------------------------------------------

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

# Equations are rendered by MathJax, which Sphinx loads from its CDN (the
# pages need a network connection to show typeset math).  To use a local copy
# instead, set ``mathjax_path`` on the command line, e.g.
# ``-D mathjax_path=file:///usr/share/javascript/mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML``
# (Debian's libjs-mathjax).

templates_path = ["_templates"]
exclude_patterns = ["_build", "_generated", "README.rst", "sphinxext", "Thumbs.db", ".DS_Store"]
source_suffix = {".rst": "restructuredtext"}
root_doc = "index"
default_role = "literal"  # `x_cc` in the guide is code, not a cross-reference
pygments_style = "sphinx"

# Fail on broken references to our own objects; references into other
# projects' documentation (scikit-learn, numpy, pandas) are plain text because
# the build must not need the network (no intersphinx).
nitpicky = False

# -- autodoc / autosummary / numpydoc ----------------------------------------

autosummary_generate = True
autosummary_generate_overwrite = True
autodoc_typehints = "none"  # the numpydoc sections carry types and units
autodoc_member_order = "bysource"
autodoc_default_options = {"inherited-members": False}

numpydoc_show_class_members = False  # the class template lists the methods
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False

# -- Gallery -----------------------------------------------------------------

sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",  # execute every plot_*.py
    "within_subsection_order": "gallery_order.ExampleOrder",
    "doc_module": ("sklearn_radar",),
    "backreferences_dir": "api/generated/backreferences",
    "reference_url": {"sklearn_radar": None},
    "remove_config_comments": True,
    "show_memory": False,
    "min_reported_time": 1,
    "download_all_examples": False,
    "matplotlib_animations": False,
    "capture_repr": ("_repr_html_", "__repr__"),
    "abort_on_example_error": False,  # report every broken example, then fail the build
}

# -- HTML --------------------------------------------------------------------

html_theme = "pydata_sphinx_theme"
html_title = f"sklearn-radar {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_show_sourcelink = False
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version", "theme-version"],
}
html_sidebars = {"index": [], "getting_started": [], "performance": []}
html_context = {"default_mode": "light"}


# -- Generated reST: the column table of sklearn_radar._schema ----------------


def _write_column_table(app):
    """Write ``_generated/columns.rst`` from the schema, the single definition of the columns."""
    from sklearn_radar import _schema

    def table(columns, caption):
        lines = [
            f".. list-table:: {caption}",
            "   :header-rows: 1",
            "   :widths: 18 10 8 64",
            "",
            "   * - column",
            "     - dtype",
            "     - unit",
            "     - meaning",
        ]
        for column in columns:
            description = re.sub(r"'([^']*)'", r"``'\1'``", column.description.replace("*", r"\*"))
            unit = r"\-" if column.unit == "-" else column.unit  # a bare "-" would start a bullet list
            lines += [f"   * - ``{column.name}``", f"     - {column.dtype}", f"     - {unit}", f"     - {description}"]
        return "\n".join(lines) + "\n"

    out = Path(app.srcdir) / "_generated"
    out.mkdir(exist_ok=True)
    text = (
        ".. This file is written by docs/conf.py from sklearn_radar._schema; do not edit.\n\n"
        + table(_schema.RADAR_DATA_COLUMNS, "The 14 RadarScenes ``radar_data`` fields")
        + "\n"
        + table(_schema.CONTEXT_COLUMNS, "Columns that sklearn-radar adds to every row")
    )
    target = out / "columns.rst"
    if not target.exists() or target.read_text(encoding="utf-8") != text:
        target.write_text(text, encoding="utf-8")


# -- Docstrings of re-exported constants ---------------------------------------

#: Private modules whose ``#:`` comments document the public constants.
_CONSTANT_MODULES = (
    "sklearn_radar._schema",
    "sklearn_radar.evaluation._filter",
    "sklearn_radar.experiments._paper",
)


def _constant_docstring(app, what, name, obj, options, lines):
    """Give a re-exported constant (e.g. ``sklearn_radar.LABELS``) the ``#:`` comment of its definition.

    autodoc reads ``#:`` comments from the module it documents, i.e. from
    ``sklearn_radar/__init__.py``, which only imports the constant, and
    otherwise falls back to the docstring of the value's type (``dict``,
    ``DataFrame``).
    """
    if what not in ("data", "attribute"):
        return
    attribute = name.rsplit(".", 1)[-1]
    from sphinx.pycode import ModuleAnalyzer

    for module_name in _CONSTANT_MODULES:
        module = importlib.import_module(module_name)
        if getattr(module, attribute, None) is not obj:
            continue
        docs = ModuleAnalyzer.for_module(module_name).find_attr_docs()
        comment = docs.get(("", attribute))
        if comment:
            lines[:] = [line.rstrip("\n") for line in comment]
            return


def _skip_member(app, what, name, obj, skip, options):
    """Leave out scikit-learn's generated ``set_*_request`` methods (metadata routing).

    scikit-learn adds them to every estimator whose ``fit`` takes metadata;
    their docstrings point into scikit-learn's own documentation.
    """
    if name.startswith("set_") and name.endswith("_request"):
        return True
    return None


# -- Workarounds for package docstrings that break the build -----------------
# Each fix applies only while the docstring still has the problem, so it
# becomes a no-op once the docstring is corrected in the package.  Reported
# to the maintainers; remove the entry when the package is fixed.


def _separate_bare_terms(lines):
    """filter_grid, Returns: ``term`` : type lines without a definition need blank lines around them."""
    term = re.compile(r"^(\s+)``[^`]+``.* : \S.*$")
    out = []
    for i, line in enumerate(lines):
        match = term.match(line)
        if match and out and out[-1].strip() and i > 0:
            previous_indent = len(lines[i - 1]) - len(lines[i - 1].lstrip())
            if previous_indent >= len(match.group(1)):
                out.append("")
        out.append(line)
    return out


def _table_as_literal(lines):
    """search_space: its simple table has a cell ("clusters") wider than its column; show it verbatim."""
    border = [i for i, line in enumerate(lines) if line.strip().startswith("====") and set(line.strip()) <= {"=", " "}]
    if len(border) < 2:
        return lines
    first, last = border[0], border[-1]
    block = lines[first : last + 1]
    try:
        from docutils.core import publish_doctree
        from docutils.utils import Reporter

        publish_doctree(
            "\n".join(line.strip() for line in block),
            settings_overrides={
                "report_level": Reporter.SEVERE_LEVEL + 1,
                "halt_level": Reporter.WARNING_LEVEL,
                "warning_stream": io.StringIO(),
            },
        )
        return lines  # the table parses: nothing to fix
    except Exception:
        pass
    indent = " " * (len(lines[first]) - len(lines[first].lstrip()))
    literal = [indent + "::", ""] + ["    " + line for line in block]
    return lines[:first] + literal + lines[last + 1 :]


_DOCSTRING_FIXES = {}


def _fix_docstring(app, what, name, obj, options, lines):
    fix = _DOCSTRING_FIXES.get(name)
    if fix is not None:
        lines[:] = fix(list(lines))


def setup(app):
    app.connect("builder-inited", _write_column_table)
    app.connect("autodoc-process-docstring", _constant_docstring, priority=400)  # before numpydoc
    app.connect("autodoc-process-docstring", _fix_docstring, priority=400)
    app.connect("autodoc-skip-member", _skip_member)
