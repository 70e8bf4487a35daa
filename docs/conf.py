"""Sphinx configuration of mechgen's documentation: offline (no intersphinx, no remote images), the analysis
kinds' reference generated from the registry (_ext/mechgen_reference.py), the gallery by sphinx-gallery.

Build: ``sphinx-build -W --keep-going -b html docs docs/_build/html`` (README, "Documentation").
"""
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "mechgen"
author = "the mechgen developers"
copyright = "the mechgen developers"

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "mechgen_reference",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "examples/README.rst", "**.ipynb_checkpoints"]
templates_path = []
html_theme = "alabaster"
html_static_path = []
html_theme_options = {"nosidebar": False}

# offline: MathJax is loaded by the reader's browser from its CDN only when a page is opened; the build itself
# fetches nothing (no intersphinx mapping, no remote images)
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
myst_heading_anchors = 3

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "reference_url": {},
    "show_memory": False,
    "show_signature": False,
    "min_reported_time": 60,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
}
