"""The command line's value checkers (argparse ``type=`` functions): each accepts a text or
raises one message naming what is valid."""

from __future__ import annotations

import argparse
import math

__all__ = ["KIND_TYPES", "positive_int", "nonnegative_int", "positive_float",
           "finite_float", "unit_fraction", "nonnegative_float", "pair", "direction",
           "angle_list", "window_size", "bounces", "bounce_count", "coatings",
           "MergeCoatings", "elevation_deg"]


def _number(parse, ok, what):
    """An argparse type: ``parse(text)`` accepted when ``ok(value)``, else one message
    naming what is valid."""
    def convert(text: str):
        """One flag's value: a number of the kind this checker names (its ``__name__``, e.g.
        "positive integer").

        Parameters
        ----------
        text : str
            The value as typed on the command line.

        Returns
        -------
        int or float
            The parsed value: an ``int`` for ``positive_int`` and ``nonnegative_int``, a
            ``float`` for the others (``positive_float``: > 0 and finite;
            ``nonnegative_float``: >= 0 and finite; ``finite_float``: finite;
            ``unit_fraction``: in (0, 1]; ``positive_int``: >= 1; ``nonnegative_int``:
            >= 0).

        Raises
        ------
        argparse.ArgumentTypeError
            When ``text`` does not parse or its value is out of range: ``must be a
            <kind>; got '<text>'``.
        """
        try:
            value = parse(text)
        except ValueError:
            value = None
        if value is None or not ok(value):
            raise argparse.ArgumentTypeError(f"must be a {what}; got {text!r}")
        return value

    convert.__name__ = what
    return convert


positive_int = _number(int, lambda v: v >= 1, "positive integer")
nonnegative_int = _number(int, lambda v: v >= 0, "non-negative integer")
positive_float = _number(float, lambda v: v > 0 and math.isfinite(v),
                         "positive finite number")
finite_float = _number(float, math.isfinite, "finite number")
#: An elevation above the x-y plane, degrees.
elevation_deg = _number(float, lambda v: -90.0 <= v <= 90.0,
                        "number of degrees from -90 to 90 (an elevation)")
unit_fraction = _number(float, lambda v: 0 < v <= 1, "number in (0, 1]")
nonnegative_float = _number(float, lambda v: v >= 0 and math.isfinite(v),
                            "non-negative finite number")
_count = _number(int, lambda v: 1 <= v <= 8, "number of bounces from 1 to 8 or 'auto'")
#: An order of bounces from 1 to 8 (``view --bounces``: no ``auto``).
bounce_count = _number(int, lambda v: 1 <= v <= 8, "number of bounces from 1 to 8")


def _items(text, what):
    """``text`` split at its commas, each item stripped; an empty item (``0,,5``, a
    trailing comma) is refused, naming its position and ``what`` is valid."""
    items = [v.strip() for v in text.split(",")]
    for k, item in enumerate(items, 1):
        if not item:
            raise argparse.ArgumentTypeError(f"item {k} of {text!r} is empty; give {what}")
    return items


def bounces(text: str):
    """An order of bounces: an integer from 1 to 8, or ``auto``.

    Parameters
    ----------
    text : str
        As typed.

    Returns
    -------
    int or str
        The integer, or ``"auto"``.

    Raises
    ------
    argparse.ArgumentTypeError
        When ``text`` is neither.
    """
    return "auto" if text == "auto" else _count(text)


def pair(text: str):
    """Two finite numbers ``U,V``.

    Parameters
    ----------
    text : str
        Two numbers separated by one comma, e.g. ``"0.1,-0.2"``.

    Returns
    -------
    tuple of float
        ``(u, v)``.

    Raises
    ------
    argparse.ArgumentTypeError
        When ``text`` is not exactly two numbers (an empty item named by its position), or
        either is not finite.
    """
    try:
        values = tuple(float(v) for v in _items(text, "two finite numbers U,V"))
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"must be two finite numbers U,V; got {text!r}")
    return values


def direction(text: str):
    """A direction ``X,Y,Z``: three finite numbers, not all zero.

    Parameters
    ----------
    text : str
        Three numbers separated by commas, e.g. ``"0,0,1"``.

    Returns
    -------
    list of float
        ``[x, y, z]`` as given (not normalised here).

    Raises
    ------
    argparse.ArgumentTypeError
        When ``text`` is not exactly three numbers (an empty item named by its position),
        one is not finite, or all three are zero.
    """
    try:
        values = [float(v) for v in _items(text, "a direction X,Y,Z")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values) or \
            not any(values):
        raise argparse.ArgumentTypeError(f"must be a direction X,Y,Z (three finite numbers, "
                                         f"not all zero); got {text!r}")
    return values


def angle_list(text: str):
    """Comma-separated finite angles in degrees.

    Parameters
    ----------
    text : str
        Numbers separated by commas, e.g. ``"0,1,5,45,90"``, spaces around them allowed.
        Any finite value is accepted (no range is imposed).

    Returns
    -------
    list of float
        The angles in degrees, in the order given (at least one).

    Raises
    ------
    argparse.ArgumentTypeError
        When an item is empty (``"0,,5"``, a trailing comma: its position is named), not a
        number, or not finite.
    """
    items = _items(text, "comma-separated numbers in degrees")
    try:
        values = [float(v) for v in items]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be comma-separated numbers in degrees; got {text!r}") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"must be finite numbers in degrees; got {text!r}")
    return values


def window_size(text):
    """WxH in pixels.

    Parameters
    ----------
    text : str
        ``WIDTHxHEIGHT``, e.g. ``"1200x900"`` (the ``x`` in either case).

    Returns
    -------
    tuple of int
        ``(width, height)`` in pixels.

    Raises
    ------
    argparse.ArgumentTypeError
        When ``text`` is not two integers separated by ``x``, or either is outside
        [1, 16384].
    """
    parts = text.lower().split("x")
    try:
        size = tuple(int(p) for p in parts)
    except ValueError:
        size = ()
    if len(size) != 2 or not all(1 <= n <= 16384 for n in size):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not WIDTHxHEIGHT in pixels, each 1-16384 (e.g. 1200x900)")
    return size


def coatings(text):
    """'part=name,part=name' → dict (names from the coating table); a part named twice is
    refused (which coating was meant cannot be guessed).

    Parameters
    ----------
    text : str
        ``PART=COATING`` pairs separated by commas, e.g. ``"small=aluminum"``; spaces
        around names are ignored. A part given the same coating twice is accepted.

    Returns
    -------
    dict of str to str
        Part (or shape) name → coating name. The names are not checked here: the scene
        loader (:func:`meshladar.cli.sources.load_source`) checks them against the coating
        table and the scene's parts.

    Raises
    ------
    argparse.ArgumentTypeError
        When an item is empty (its position named), has no ``=``, or a part is given two
        different coatings.
    """
    out = {}
    for item in _items(text, "PART=COATING pairs"):
        if "=" not in item:
            raise argparse.ArgumentTypeError(f"must be PART=COATING pairs; got {item!r}")
        k, v = (x.strip() for x in item.split("=", 1))
        if k in out and out[k] != v:
            raise argparse.ArgumentTypeError(f"part {k!r} is given two coatings ({out[k]!r} and "
                                             f"{v!r}); give each part one")
        out[k] = v
    return out


class MergeCoatings(argparse.Action):
    """``--coating`` given more than once: the pairs of every use, merged; a part given two
    different coatings across them is refused, as within one."""

    def __call__(self, parser, namespace, values, option_string=None):
        merged = dict(getattr(namespace, self.dest, None) or {})
        for k, v in values.items():
            if k in merged and merged[k] != v:
                parser.error(f"argument {option_string}: part {k!r} is given two coatings "
                             f"({merged[k]!r} and {v!r}); give each part one")
            merged[k] = v
        setattr(namespace, self.dest, merged)


#: :class:`meshladar.forward.options.Option` kinds → the checker that parses them.
KIND_TYPES = {"positive_float": positive_float, "nonnegative_float": nonnegative_float,
              "finite_float": finite_float, "unit_fraction": unit_fraction,
              "positive_int": positive_int, "nonnegative_int": nonnegative_int,
              "direction": direction, "pair": pair, "path": str, "bounces": bounces}
