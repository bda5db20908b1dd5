"""Sphinx configuration of meshladar's documentation site.

Build it (offline, from the repository alone; warnings are errors, cross-references
checked) with::

    .venv/bin/python -m sphinx -W -n -b html docs docs/_build/html
"""

from __future__ import annotations

import os
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import meshladar  # noqa: E402

project = "meshladar"
author = "the meshladar developers"
copyright = "2026, the meshladar developers"
release = version = meshladar.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "myst_parser",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "cli_reference",
    "resolve_refs",
    "validation",
    "notebooks",
]

html_theme = "pydata_sphinx_theme"
html_title = "meshladar"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path: list = []
exclude_patterns = ["_build", "gallery"]
# the guide's pages are Markdown (MyST), so that their text reads on GitHub as well and the test
# suite runs their examples as it runs the README's; ::: fences hold directives (images,
# includes) where a ``` fence would read as code
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3
# flags stay as typed: "--views", not an en dash
smartquotes = False
templates_path: list = []

# cross-references are checked (-n); the types in numpydoc's Parameters are prose (shapes,
# units), not links, and numpy's and Python's own names have no inventory offline
nitpicky = True
numpydoc_xref_param_type = False
numpydoc_show_class_members = False
numpydoc_validation_checks: set = set()
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|scipy|trimesh|pyvista|matplotlib|dask|concurrent|argparse|"
               r"pathlib|os|typing|collections|warnings|functools|contextlib)\..*"),
    (r"py:class", r"(ndarray|optional|callable|array_like|float|int|str|bool|dict|list|"
                  r"tuple|object|None|path-like|sequence|mapping)"),
]

autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_member_order = "bysource"
autodoc_typehints = "none"

sphinx_gallery_conf = {
    "examples_dirs": str(HERE / "gallery"),
    "gallery_dirs": "auto_gallery",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "min_reported_time": 1e9,
    "within_subsection_order": "FileNameSortKey",
}


def _public_modules():
    """Every public module's dotted name (no ``_`` part), the deprecated aliases apart."""
    import importlib
    import pkgutil
    import warnings

    out = []
    for package in ("meshladar", "meshladar.phantoms", "meshladar.viz"):
        paths = importlib.import_module(package).__path__
        for info in pkgutil.walk_packages(paths, package + "."):
            if any(p.startswith("_") for p in info.name.split(".")[1:]):
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("error", DeprecationWarning)
                try:
                    importlib.import_module(info.name)
                except DeprecationWarning:
                    continue
            out.append(info.name)
    return out


def _defined_here(obj, dotted):
    """Whether module ``dotted`` is where ``obj`` is documented: it is defined there, or in
    a private module, or its home module does not export it (a value a function made, such
    as a command's translator made by ``flag_words``)."""
    import importlib

    home = getattr(obj, "__module__", None) or dotted
    if home == dotted or any(part.startswith("_") for part in home.split(".")):
        return True
    exported = getattr(importlib.import_module(home), "__all__", ())
    return not any(getattr(importlib.import_module(home), n, None) is obj for n in exported)


def _uncovered(packages):
    """{module: [names]}: the public names a module defines (``__all__``) that no page of
    ``packages`` documents (no package above it re-exports them)."""
    import importlib

    covered = set()
    for name in packages:
        module = importlib.import_module(f"meshladar.{name}")
        covered |= {id(getattr(module, n, None)) for n in getattr(module, "__all__", ())}
    out = {}
    for dotted in _public_modules():
        module = importlib.import_module(dotted)
        names = [n for n in getattr(module, "__all__", ())
                 if id(getattr(module, n, None)) not in covered
                 and _defined_here(getattr(module, n, None), dotted)]
        if names and dotted.removeprefix("meshladar.") not in packages:
            out[dotted] = names
    return out


def _api_pages():
    """One reference page per public submodule (``meshladar._SUBMODULES``, in layer order),
    and one per module whose public names its package does not re-export (those names
    only), written at each build: the reference cannot miss a public name."""
    folder = HERE / "reference" / "api"
    folder.mkdir(parents=True, exist_ok=True)
    pages = {}
    for name in meshladar._SUBMODULES:
        title = f"meshladar.{name}"
        pages[name] = f"{title}\n{'=' * len(title)}\n\n.. automodule:: {title}\n"
    for dotted, names in _uncovered(meshladar._SUBMODULES).items():
        pages[dotted.removeprefix("meshladar.")] = (
            f"{dotted}\n{'=' * len(dotted)}\n\n.. automodule:: {dotted}\n"
            f"   :members: {', '.join(names)}\n")
    for name, text in pages.items():
        page = folder / f"{name}.rst"
        if not page.exists() or page.read_text() != text:
            page.write_text(text)
    for stale in folder.glob("*.rst"):         # a module renamed or removed since
        if stale.stem != "index" and stale.stem not in pages:
            stale.unlink()
    index = ("API reference\n=============\n\nEvery public module, in the engine's layer "
             "order (foundation first), then the modules whose names their package does not "
             "re-export. The commonly used names are also ``meshladar.<name>``.\n\n"
             ".. toctree::\n   :maxdepth: 1\n\n" + "".join(f"   {n}\n" for n in pages))
    (folder / "index.rst").write_text(index)


_api_pages()
