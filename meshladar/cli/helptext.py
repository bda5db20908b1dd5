"""A command's ``--help`` description from its function's docstring: the prose before the
numpydoc sections (which document the function for the API reference, not the user), its
reST roles and literals as plain text (``:func:`a.b``` as a.b(), ``:class:`~a.B``` as B,
````x```` as x) and each paragraph filled again to the width the markup left uneven."""

from __future__ import annotations

import inspect
import re
import textwrap

__all__ = ["description", "WIDTH"]

#: The width a description's paragraphs are filled to (the docstrings' own).
WIDTH = 88
#: A numpydoc section heading: a line of words under a line of dashes.
_SECTION = re.compile(r"^\w[\w ]*\n-{3,}$", re.MULTILINE)
#: A reST role (its ~ and an explicit title's target dropped) or an inline literal.
_ROLE = re.compile(r":(\w+):`(~?)([^`<]*?)(?: <[^`]*>)?`|``([^`]+)``")


def description(command):
    """The ``--help`` description of ``command`` (module docstring).

    Parameters
    ----------
    command : callable
        A command's function; its docstring is the description.

    Returns
    -------
    str
        Plain paragraphs separated by blank lines ("" for no docstring).
    """
    text = inspect.cleandoc(command.__doc__ or "")
    cut = _SECTION.search(text)
    text = _ROLE.sub(_plain, text[:cut.start()].rstrip() if cut else text)
    return "\n\n".join(_fill(p) for p in text.split("\n\n"))


def _plain(match):
    role, tilde, name, literal = match.groups()
    if literal is not None:
        return literal
    name = name.rsplit(".", 1)[-1] if tilde else name
    return name + "()" if role in ("func", "meth") else name


def _fill(paragraph):
    """A paragraph of prose filled to :data:`WIDTH`; one with indented or bulleted lines
    (a list, an example) as it is."""
    lines = paragraph.splitlines()
    if any(line[:1].isspace() or line.lstrip()[:2] in ("- ", "* ") for line in lines):
        return paragraph
    return textwrap.fill(" ".join(lines), WIDTH)
