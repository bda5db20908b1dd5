"""API messages in a command's own words: each command's errors and warnings come from the
API, which names its parameters (``ray_spacing``, ``mode='3d'``); the command line names
its flags (``--ray-spacing``, ``--mode 3d``). :func:`flag_words` makes a command's
translator from the table of its flags; :mod:`meshladar.cli` applies it, at one place, to
every message the command prints.
"""

from __future__ import annotations

import re

__all__ = ["flag_words"]


def flag_words(flags, anywhere=(), phrases=()):
    """A translator of API messages into a command's flags.

    Parameters
    ----------
    flags : dict of str to str
        Each API name the command sets, with its flag (``{"n_bins": "--bins"}``).
    anywhere : iterable of str
        The names a message uses only for their values (an underscore in them:
        ``ray_spacing``): their flag wherever they stand outside quotes and outside a
        path (a file's name is kept, quoted or not: ``/data/n_bins/part.stl``). The other
        names (``size``, ``tol``: words of prose too) become their flag only where a
        message begins with one as the subject of a rule (``size must be ...``,
        ``size: ...``).
    phrases : iterable of (str, str)
        Whole phrases replaced last (an API's advice with no one flag to name).

    Returns
    -------
    callable
        ``words(message) -> str``: ``name='value'`` and ``name=value`` become ``--flag
        value`` for every name in ``flags`` outside quotes and paths (``name=True`` the flag
        alone, ``name=False`` and ``name=None`` ``no --flag``), then the rules above.
    """
    flags = dict(flags)
    unique = sorted(anywhere, key=len, reverse=True)
    others = [n for n in flags if n not in unique]
    everywhere = re.compile(r"(?<!\w)('[^']*'|\"[^\"]*\")|(?<![-\w./\\])(" + "|".join(unique)
                            + r")\b(?![./\\]\w)") if unique else None
    leading = re.compile(r"^(" + "|".join(others) + r")(?= must\b|:)") if others else None
    assigned = re.compile(r"(?<!\w)('[^']*'|\"[^\"]*\")|(?<![-\w./\\])(" + "|".join(flags)
                          + r")=(?:'([^']*)'|([\w.+-]+))(?![\w/\\])")
    phrases = tuple(phrases)

    def words(message):
        message = assigned.sub(lambda m: m.group(1) or _set(flags[m.group(2)],
                                                            m.group(3) or m.group(4)),
                               message)
        if everywhere is not None:
            message = everywhere.sub(lambda m: m.group(1) or flags[m.group(2)], message)
        if leading is not None:
            message = leading.sub(lambda m: flags[m.group(1)], message)
        for api, text in phrases:
            message = message.replace(api, text)
        return message

    return words


def _set(flag, value):
    """``flag value`` as typed: a switch's True is the flag alone, its False (or a value
    None) no flag."""
    if value == "True":
        return flag
    if value in ("False", "None"):
        return f"no {flag}"
    return f"{flag} {value}"
