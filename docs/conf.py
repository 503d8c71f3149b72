"""Sphinx configuration: the slipchain site (PyData theme, Markdown pages via MyST, API from
docstrings via autodoc + napoleon, a gallery of executed examples via sphinx-gallery).

    make docs        # -> docs/_build/html (warnings are errors)
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
os.environ.setdefault("NUMBA_CACHE_DIR", str(ROOT / ".numba_cache"))

from slipchain import __version__  # noqa: E402

project = "slipchain"
author = "the slipchain developers"
copyright = "2026, the slipchain developers"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into the site: equations render without network
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.md5", "auto_examples/*.json", "**/SYNTHETIC-README.txt"]
suppress_warnings = ["myst.header"]  # committed reports start at level-2 headings

autosummary_generate = True
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
napoleon_numpy_docstring = True
napoleon_google_docstring = False

# The gallery: short scripts in examples/, executed at every build (so they cannot rot); their
# figures and output land in auto_examples/. SLIPCHAIN_DOCS_GALLERY=0 builds without running them.
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "plot_gallery": os.environ.get("SLIPCHAIN_DOCS_GALLERY", "1") != "0",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "capture_repr": (),  # show what the examples print, not the repr of their last expression
}

html_theme = "pydata_sphinx_theme"
html_title = f"slipchain {__version__}"
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "getting-started": []}
html_static_path: list[str] = []

# linkcheck: the internal links only (the build machines have no network).
linkcheck_ignore = [r"https?://.*"]


# Docstrings write absolute values as |u| (plain text, as in MODEL.md); reST would read |u| as a
# substitution. Escape such pipes outside ``literal`` spans before autodoc parses them.
import re  # noqa: E402

_LITERAL = re.compile(r"(``.*?``)")
_ABS = re.compile(r"(?<![\\|])\|(?=[^\s|])([^|\n]*?[^\s\\|])\|(?!\|)")


def _escape_abs(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        if line.lstrip().startswith(("|", "+-", "+=")):  # a table row
            continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(p if p.startswith("``") else _ABS.sub(r"\\|\1\\|", p) for p in parts)


def setup(app):
    app.connect("autodoc-process-docstring", _escape_abs)
