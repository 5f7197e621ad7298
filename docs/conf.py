"""Sphinx configuration of the toolpoint documentation (``make docs``; warnings are errors)."""

import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))
os.environ.setdefault("MPLBACKEND", "Agg")

import toolpoint  # noqa: E402

project = "toolpoint"
author = "the toolpoint developers"
copyright = "2026, the toolpoint developers (MIT licence)"
release = version = toolpoint.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx.ext.intersphinx",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "img/README*"]
templates_path = ["_templates"]

autosummary_generate = True
autodoc_default_options = {
    "members": True,
    "show-inheritance": False,
    # scikit-learn adds these metadata-routing methods to every estimator: not toolpoint API
    "exclude-members": "set_fit_request,set_predict_request,set_score_request,set_params,get_params",
}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

myst_heading_anchors = 3
suppress_warnings = ["myst.xref_missing", "myst.header"]

intersphinx_mapping = {
    "python": ("https://docs.python.org/3", None),
}
intersphinx_disabled_reftypes = ["*"]
# No network in CI: intersphinx inventories are not fetched (links stay plain text).
intersphinx_mapping = {}

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
}

html_theme = "alabaster"
html_title = f"toolpoint {release}"
html_static_path = []


# Docstrings write absolute values as |x| (plain text reads better than :math:); reST would take them for
# substitutions. Escape a bar outside inline literals and outside table/line-block lines.
_LITERAL = re.compile(r"(``.*?``|:math:`[^`]*`)")


def _escape_bars(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        if ":mod:`." in line or ":func:`." in line or ":class:`." in line:
            # relative cross-references (:mod:`.uncertainty`) resolve against the docstring's own package
            line = lines[i] = _REL.sub(lambda m: f"{m.group(1)}`{_package(what, name, obj)}.", line)
        if "|" not in line or stripped.startswith(("| ", "+")):
            continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(p if k % 2 else p.replace("|", r"\|") for k, p in enumerate(parts))


_REL = re.compile(r"(:(?:mod|func|class|meth|attr|data):)`\.")


def _package(what, name, obj):
    import importlib

    mod = name if what == "module" else getattr(obj, "__module__", None) or name.rpartition(".")[0]
    try:
        is_pkg = hasattr(importlib.import_module(mod), "__path__")
    except ImportError:
        is_pkg = False
    return mod if is_pkg else mod.rpartition(".")[0]


def _skip_member(app, what, name, obj, skip, options):
    # scikit-learn generates set_*_request methods for metadata routing on every estimator: not our API.
    if name.startswith("set_") and name.endswith("_request"):
        return True
    return skip


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("autodoc-skip-member", _skip_member)
