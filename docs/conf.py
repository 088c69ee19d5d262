"""Sphinx configuration of wearcheck's documentation site.

Build (warnings are errors)::

    pip install -e ".[docs]"
    python -m sphinx -W --keep-going -b html docs docs/_build/html

Why Sphinx (MyST, autodoc + numpydoc, sphinx-gallery) rather than
mkdocs-material (mkdocstrings, mkdocs-jupyter), measured on this project's
pages plus one executed example, 2026-11-27: a comparable build took 5.7 s
and 4.1 s; the install was 40 packages, about 120 MB (Sphinx stack) against
84 packages, about 250 MB (the mkdocs stack, most of it the Jupyter kernel
that executes notebooks). sphinx-gallery runs the examples/ scripts as they
are, in the build's own interpreter (no kernel, no notebooks to keep in
step with the tests, which run the same scripts), and offers each as a
script and a notebook download; autodoc imports the real objects, numpydoc
reads the docstrings as written; ``-W --keep-going`` turns every warning
(broken link, bad cross-reference, a failing example) into an error and
lists them all.

What is generated at build time (``_ext/wearcheck_docs.py``, into
``_generated/``): the case-key table (from ``cases/schema.py``), the output
tables (from ``wearcheck/layout.py``) and the command reference (from
the ``wearcheck`` argument parser), so they cannot go stale.
"""

import logging
import os
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

import wearcheck  # noqa: E402

# scikit-fem reports every assembly at INFO, Dask every worker's start and stop
# (its own configuration, read when distributed is first imported, also by the
# worker processes); the build log is for warnings
logging.getLogger("skfem").setLevel(logging.WARNING)
os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "warning")

project = "wearcheck"
author = "the wearcheck authors"
copyright = "the wearcheck authors, MIT licence"
release = wearcheck.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "wearcheck_docs",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_generated/*.md", "tutorials/*.ipynb", "tutorials/*.py",
                    "tutorials/*.md5", "tutorials/*.json", "tutorials/*.zip"]
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence", "dollarmath"]
# Markdown links to files outside the site (examples/, benchmarks/, cases/)
# point at the repository files; the site links them as plain URLs
myst_url_schemes = ["http", "https", "mailto"]
suppress_warnings = []

autodoc_member_order = "bysource"
autodoc_typehints = "none"          # numpydoc writes the types from the docstrings
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()  # style is reviewed, not enforced by the build

html_theme = "furo"
html_title = f"wearcheck {release}"
html_static_path = []

# The tutorials: the repository's examples/ scripts, executed at every build.
# sphinx-gallery runs each script with its folder as working directory; the
# scripts write run directories and figures there, so the build runs a copy
# in _build/ and leaves examples/ untouched.
GALLERY_SOURCE = HERE / "_build" / "gallery-src"
if GALLERY_SOURCE.exists():
    shutil.rmtree(GALLERY_SOURCE)
shutil.copytree(HERE.parent / "examples", GALLERY_SOURCE,
                ignore=shutil.ignore_patterns("runs", "__pycache__", "*.png", "*.toml"))

sphinx_gallery_conf = {
    "examples_dirs": str(GALLERY_SOURCE),
    "gallery_dirs": "tutorials",
    "filename_pattern": "/",            # execute every script
    "abort_on_example_error": True,     # a failing tutorial fails the build
    "within_subsection_order": "wearcheck_docs.tutorial_order",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "show_memory": False,
    "plot_gallery": "True",
}
