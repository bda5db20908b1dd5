"""Short reprs for results: a one-line summary (shape, model, range, units, conventions)
instead of whole arrays, and the same as an HTML table for notebooks."""

from __future__ import annotations

import html

__all__ = ["text", "table", "listing", "material_name", "scene_summary"]

#: The longest repr a result gives (tested).
MAX_REPR = 400


def _fmt(v):
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, tuple) and v and all(isinstance(x, float) for x in v):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
    return repr(v) if isinstance(v, str) else str(v)


def _fields(fields):
    return [(k, v) for k, v in fields if v is not None]


def text(name, *fields):
    """``Name(key=value, ...)`` of the (key, value) pairs that are not None, shortened to
    :data:`MAX_REPR` characters."""
    body = ", ".join(f"{k}={_fmt(v)}" for k, v in _fields(fields))
    out = f"{name}({body})"
    return out if len(out) <= MAX_REPR else out[:MAX_REPR - 4] + "...)"


def table(name, *fields):
    """The same pairs as an HTML table headed by ``name`` (a notebook's rich repr)."""
    rows = "".join(f"<tr><th style='text-align:left'>{html.escape(str(k))}</th>"
                   f"<td style='text-align:left'>"
                   f"{html.escape(v if isinstance(v, str) else _fmt(v))}</td></tr>"
                   for k, v in _fields(fields))
    return (f"<table><caption style='text-align:left'><b>{html.escape(name)}</b></caption>"
            f"{rows}</table>")


def listing(items, most=4):
    """``a, b, c, d, ... (+n more)``: a short list of names for a summary."""
    items = [str(i) for i in items]
    more = len(items) - most
    return ", ".join(items[:most]) + (f", ... (+{more} more)" if more > 0 else "")


def material_name(material):
    """A coating's name, or its class for an unnamed BRDF."""
    return getattr(material, "name", None) or type(material).__name__


def scene_summary(scene):
    """The (label, value) rows of a Scene's repr: its kind, parts or shapes, materials,
    bounds or bounding circle."""
    mats = listing(dict.fromkeys(material_name(m) for m in scene.materials))
    if scene.parts:
        lo, hi = scene.bounds()
        rep = scene.report
        return (("kind", "mesh"),
                ("parts", listing(f"{p.name}: {len(p.faces)} faces" for p in scene.parts)),
                ("faces", rep.get("faces")), ("materials", mats),
                ("bounds", f"[{', '.join(f'{a:.4g}' for a in lo)}] to "
                           f"[{', '.join(f'{b:.4g}' for b in hi)}]"),
                ("watertight", all(rep.get("watertight") or [False])),
                ("inverted_bodies", rep.get("inverted_bodies") or None))
    (cx, cy), r = scene.bounding_circle()
    return (("kind", "analytic"),
            ("shapes", listing(f"{s.name or type(s).__name__}: {type(s).__name__}"
                               for s in scene.shapes)),
            ("materials", mats), ("bounding_circle", f"center ({cx:.4g}, {cy:.4g}), "
                                                     f"radius {r:.4g}"))
