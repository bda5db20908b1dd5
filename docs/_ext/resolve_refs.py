"""Cross-references written as the code names things, resolved to where the site documents
them.

The reference documents each public name at its package (``meshladar.reconstruct.fbp``,
as scikit-image documents ``skimage.transform.radon``), while docstrings may name its
defining module (``meshladar.reconstruct.fbp2d.fbp``), a top-level alias
(``meshladar.simulate``), or a name relative to their own module (``weigh``, ``parser``).
On a reference Sphinx cannot find, this finds the Python object the name means and links
to the documented name of the same object; an object the site does not document by itself
(a module, a constant, a helper a docstring mentions) links to the nearest documented
module above it. A name with a private part (``_x``) is shown as code, unlinked: private
names are not documented. Anything else stays a broken reference (a warning; the build
runs with ``-W -n``).
"""

from __future__ import annotations

import importlib
import re

from docutils import nodes
from sphinx.addnodes import pending_xref
from sphinx.util.nodes import make_refnode


def _lookup(dotted):
    """The object a dotted name means (a module or an attribute path), else None."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except Exception:                                    # noqa: BLE001 - not a module
            continue
        try:
            for name in parts[cut:]:
                obj = getattr(obj, name)
        except AttributeError:
            return None
        return obj
    return None


def _candidates(target, contexts):
    """The dotted names ``target`` may mean, written in the modules ``contexts`` (the page's
    module, and the object whose docstring holds it: a re-exported function's docstring
    names things as its defining module sees them)."""
    out = [target]
    for context in contexts:
        parts = context.split(".")
        out += [".".join(parts[:k] + [target]) for k in range(len(parts), 0, -1)]
    out.append(f"meshladar.{target}")
    return out


def _documented(env):
    """id(object) → (documented name, docname, anchor) of everything the site documents (a
    module's anchor is ``module-<name>``, not its name)."""
    cache = getattr(env, "_meshladar_anchors", None)
    if cache is None:
        cache = {}
        for name, entry in env.get_domain("py").objects.items():
            obj = _lookup(name)
            if obj is not None:
                cache.setdefault(id(obj), (name, entry.docname, entry.node_id))
        env._meshladar_anchors = cache
    return cache


def _resolve(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    contexts = [c for c in (node.get("py:module"), *_DOCSTRING_OF.findall(node.source or ""))
                if c]
    documented = _documented(env)
    for name in _candidates(target, contexts):
        obj = _lookup(name)
        if obj is None:
            continue
        found = documented.get(id(obj))
        if found is None:                       # the nearest documented module above it
            parts = name.split(".")
            for k in range(len(parts) - 1, 0, -1):             # the nearest documented package
                found = documented.get(id(_lookup(".".join(parts[:k]))))
                if found:
                    break
        if found:
            return make_refnode(app.builder, node["refdoc"], found[1], found[2], contnode,
                                found[0])
    if any(part.startswith("_") for part in target.split(".")):
        return nodes.literal(text=node.astext())
    return None


_DOCSTRING_OF = re.compile(r"docstring of ([\w.]+)")
#: ``|x|`` in a docstring is an absolute value or a norm, not a substitution (meshladar
#: defines none): escaped for the site, so the docstrings stay plain text in a terminal.
_BARS = re.compile(r"(?<![\\|\w`])\|(?=[^\s|])([^|\n`]*?[^\s|\\])\|(?![|\w])")


def _escape_bars(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        row = line.strip()
        if not (row[:1] in "|+" and row[-1:] in "|+" and row):      # not a table's row
            lines[i] = _BARS.sub(r"\\|\1\\|", line)


def setup(app):
    app.connect("missing-reference", _resolve)
    app.connect("autodoc-process-docstring", _escape_bars)
    return {"parallel_read_safe": True, "version": "1"}
