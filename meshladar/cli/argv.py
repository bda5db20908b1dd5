"""The command line's words before argparse reads them: a negative comma list after a flag
(``--angles-deg -10,10``, ``--receiver -1,0,0``, ``--beam-offset -0.1,0``) is that flag's
value, as ``--angles-deg=-10,10`` would be.

argparse takes a word beginning with ``-`` for an option unless it is a plain negative
number (``-10``, ``-0.5``): ``-10,10`` is not one, so ``--angles-deg -10,10`` failed with
"expected one argument". :class:`Parser` joins such a word to the flag before it.
"""

from __future__ import annotations

import argparse
import re
import sys

__all__ = ["Parser", "join_negative_lists"]

#: A long flag without its value attached.
_FLAG = re.compile(r"--[A-Za-z][\w-]*")
#: A comma list whose first item is a negative number (``-10,10``, ``-.5,0``, ``-inf,0``,
#: ``-1,,2``: the list's own checker judges its items).
_NEGATIVE_LIST = re.compile(r"-(?:\d|\.\d|inf|nan)[^,]*(?:,[^,]*)+", re.IGNORECASE)


def join_negative_lists(words):
    """``words`` with each negative comma list that follows a long flag joined to it.

    Parameters
    ----------
    words : list of str
        The command line's words after the program's name.

    Returns
    -------
    list of str
        The same words, ``["--angles-deg", "-10,10"]`` becoming ``["--angles-deg=-10,10"]``;
        nothing after a bare ``--`` (the end of the options) is changed.

    Examples
    --------
    >>> join_negative_lists(["simulate", "x.stl", "--receiver", "-1,0,0", "--z0", "-1"])
    ['simulate', 'x.stl', '--receiver=-1,0,0', '--z0', '-1']
    """
    out = []
    for word in words:
        if "--" in out:
            out.append(word)
        elif out and _FLAG.fullmatch(out[-1]) and _NEGATIVE_LIST.fullmatch(word):
            out[-1] = f"{out[-1]}={word}"
        else:
            out.append(word)
    return out


class Parser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` that reads a negative comma list after a flag as
    its value (:func:`join_negative_lists`); its subcommands' parsers are of this class
    too."""

    def parse_known_args(self, args=None, namespace=None):
        """argparse's, on the words with their negative lists joined to their flags.

        Parameters
        ----------
        args : list of str, optional
            The words (default ``sys.argv[1:]``).
        namespace : argparse.Namespace, optional
            Where to store the values (default a new one).

        Returns
        -------
        tuple
            ``(namespace, remaining words)``, as argparse's.
        """
        words = sys.argv[1:] if args is None else list(args)
        return super().parse_known_args(join_negative_lists(words), namespace)
