"""Sphinx configuration of the vpcontact documentation.

Build it from the repository's root with ``python -m sphinx -W -b html docs build/html`` (``pip install
".[docs]"``). The pages are the Markdown files of this folder (myst-parser), the API reference from the
docstrings (autodoc) and the gallery of ``examples/plot_*.py`` (sphinx-gallery, which runs each example and
writes its page and figures into ``gallery/``).
"""

import logging
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # figure_scraper
sys.path.insert(0, str(HERE.parent / "src"))  # vpcontact from this source tree, installed or not

project = "vpcontact"
author = "the vpcontact authors"
copyright = "the vpcontact authors, MIT licence"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "build", "examples/README.rst", "gallery/*.ipynb", "gallery/*.py"]

# --- Markdown pages -------------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3  # [Outputs](#outputs) links to a heading of the same page

# --- API reference ----------------------------------------------------------------------------------
default_role = "py:obj"  # `name` in a docstring links to that object when there is one
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}

# --- gallery ------------------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",  # run every example
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": ("figure_scraper.scrape",),  # vpcontact.results.plots returns Figures without pyplot
    "ignore_repr_types": r"matplotlib\.figure\.Figure",  # a block's last Figure is an image, not its repr
    "download_all_examples": False,
    "remove_config_comments": True,
}

logging.getLogger("skfem").setLevel(logging.WARNING)  # not a line per basis scikit-fem builds

# --- HTML ----------------------------------------------------------------------------------------------
html_theme = "furo"
html_title = "vpcontact"
