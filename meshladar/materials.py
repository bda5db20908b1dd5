"""Coatings: the paper's two SR coatings, simple helpers, and TOML material tables.

``DARK_GRAY`` and ``ALUMINUM`` are the Sandford-Robertson fits at λ = 1 µm used in the
paper's Sec. 4.B (Figs 9-11). A material table is a TOML file with one table per
material::

    [dark_gray]
    description = "dark gray paint, 1 µm (Jin & Levine 2009, Sec. 4.B)"   # optional
    rho_d = 0.032
    epsilon = 0.877
    b = 0.1
    e = 0.17
    lobes = "both"                                                         # optional

``load_table(path)`` reads one with the same validation as :class:`SandfordRobertson`,
and an error names the file, the entry and the field. The paper's coatings are such a
table, ``materials.toml`` beside this module (:data:`TABLE_PATH`): the one source of their
numbers, read once at import into :data:`PAPER`; ``DARK_GRAY`` and ``ALUMINUM`` are two of
its entries, and the phantom library and the CLI name coatings from it.
"""

from __future__ import annotations

import tomllib
from importlib import resources
from types import MappingProxyType

from .brdf import SandfordRobertson
from ._validate import check_path, check_real
from .errors import MaterialFileError

__all__ = ["read_toml", "DARK_GRAY", "ALUMINUM", "PAPER", "TABLE_PATH", "lambertian", "glint",
           "load_table", "parse_table"]

_FIELDS = {"rho_d": float, "epsilon": float, "b": float, "e": float, "lobes": str,
           "description": str}
_REQUIRED = ("rho_d", "epsilon", "b", "e")


def lambertian(rho_d=1.0, *, name=None):
    """A Lambertian coating: F = ρd/π at every angle (SR with b = 0, diffuse lobe only).

    Parameters
    ----------
    rho_d : float
        Diffuse reflectivity ρd, in [0, 1] (default 1.0).
    name : str, optional
        A label for tables and reprs. Keyword-only.

    Returns
    -------
    SandfordRobertson
        ``SandfordRobertson(rho_d=rho_d, epsilon=0, b=0, e=1, lobes="diffuse")``.

    Raises
    ------
    ParameterError
        When ``rho_d`` is not a finite real in [0, 1], or ``name`` is neither a str nor
        None.

    References
    ----------
    Jin & Levine (2009), Eqs. A1-A3 with b = 0 (g ≡ 1, G = 1).

    Examples
    --------
    >>> import numpy as np
    >>> from meshladar.materials import lambertian
    >>> bool(np.isclose(lambertian(0.5).monostatic(0.3), 0.5 / np.pi))   # at any angle
    True
    """
    return SandfordRobertson(rho_d=rho_d, epsilon=0.0, b=0.0, e=1.0, lobes="diffuse", name=name)


def glint(e, rho_s=1.0, *, name=None):
    """A pure glint coating: the specular lobe alone with constant reflectivity ρs.

    With b = 0 the SR reflectivity A8 is ρs = 1 − ε, so ε = 1 − ρs; ``glint(e)`` is the
    paper's Fig. 8 surface (ρs = 1, ε = ρd = 0).

    Parameters
    ----------
    e : float
        Glint eccentricity, in [1e-12, 1] (A6): small values are mirror-like.
    rho_s : float
        Specular reflectivity ρs, in [0, 1] (default 1.0).
    name : str, optional
        A label for tables and reprs. Keyword-only.

    Returns
    -------
    SandfordRobertson
        ``SandfordRobertson(rho_d=0, epsilon=1 − rho_s, b=0, e=e, lobes="specular")``.

    Raises
    ------
    ParameterError
        When ``rho_s`` or ``e`` is not a finite real in its range, or ``name`` is neither
        a str nor None.

    References
    ----------
    Jin & Levine (2009), Eqs. A5-A8 and Fig. 8.

    Examples
    --------
    >>> import numpy as np
    >>> from meshladar.materials import glint
    >>> aluminium_like = glint(e=0.007)
    >>> f = aluminium_like.monostatic(np.array([0.0, 0.01]))   # 0.01 rad off the mirror
    >>> bool(f[1] < 0.2 * f[0])                      # the lobe is 0.007 wide
    True
    """
    epsilon = 1.0 - check_real("rho_s", rho_s, low=0.0, high=1.0)
    return SandfordRobertson(rho_d=0.0, epsilon=epsilon, b=0.0, e=e, lobes="specular", name=name)


def parse_table(data, *, source="<table>"):
    """Build materials from a mapping ``{name: {field: value}}`` (a parsed TOML table).

    Returns a read-only mapping of name to :class:`SandfordRobertson`. Errors are
    :class:`~meshladar.errors.MaterialFileError` naming ``source``, the entry and the field.

    Parameters
    ----------
    data : dict
        ``{name: {field: value}}``: per material the numbers ``rho_d``, ``epsilon``, ``b``
        and ``e`` (required) and the strings ``lobes`` (default ``"both"``) and
        ``description`` (optional, not stored); at least one material.
    source : str
        What the table came from, for the messages (default ``"<table>"``).
        Keyword-only.

    Returns
    -------
    types.MappingProxyType
        Read-only mapping of each entry's name to its :class:`SandfordRobertson` (named
        after the entry).

    Raises
    ------
    MaterialFileError
        When ``data`` is not a non-empty dict, an entry is not a table, has an unknown or
        missing field or a field of the wrong type (a bool is not a number), or its values
        are refused by :class:`SandfordRobertson`.
    """
    if not isinstance(data, dict) or not data:
        raise MaterialFileError(f"{source}: expected at least one [material] table; got none")
    out = {}
    for entry, spec in data.items():
        where = f"{source}: material [{entry}]"
        if not isinstance(spec, dict):
            raise MaterialFileError(f"{where} must be a table of fields; got {spec!r}")
        unknown = sorted(set(spec) - set(_FIELDS))
        if unknown:
            raise MaterialFileError(
                f"{where}: unknown field {unknown[0]!r}; valid fields are {tuple(_FIELDS)}")
        missing = [f for f in _REQUIRED if f not in spec]
        if missing:
            raise MaterialFileError(f"{where}: missing field {missing[0]!r}")
        for f, kind in _FIELDS.items():
            if f not in spec:
                continue
            v = spec[f]
            ok = isinstance(v, str) if kind is str else (
                isinstance(v, (int, float)) and not isinstance(v, bool))
            if not ok:
                raise MaterialFileError(
                    f"{where}: field {f!r} must be a {'string' if kind is str else 'number'}; "
                    f"got {v!r}")
        try:
            out[entry] = SandfordRobertson(
                rho_d=spec["rho_d"], epsilon=spec["epsilon"], b=spec["b"], e=spec["e"],
                lobes=spec.get("lobes", "both"), name=entry)
        except ValueError as exc:
            raise MaterialFileError(f"{where}: {exc}") from exc
    return MappingProxyType(out)


def load_table(path):
    """Read a TOML material table; see the module docstring for its format.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.

    Returns
    -------
    Mapping[str, SandfordRobertson]
        Read-only mapping of each material's name to its coating (:func:`parse_table`).

    Raises
    ------
    ParameterError
        When ``path`` is not a non-empty str or os.PathLike.
    MaterialFileError
        When the file cannot be read or parsed, or an entry is invalid (naming the file,
        the entry and the field).
    """
    path = check_path("path", path)
    return parse_table(read_toml(path, "material table", MaterialFileError), source=path)


def read_toml(path, what, error):
    """Parse a TOML file, turning every way it can fail into one ``error`` naming the file:
    unreadable, not UTF-8, not TOML, nested too deeply, numbers too long to parse.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.
    what : str
        What the file should be (e.g. ``"material table"``), for the messages.
    error : type
        The exception class to raise, called with the message (e.g.
        :class:`~meshladar.errors.MaterialFileError`).

    Returns
    -------
    dict
        The parsed TOML document.

    Raises
    ------
    error
        When the file cannot be opened or read (OSError), is not UTF-8, is not valid TOML,
        is nested too deeply, or holds a value Python cannot parse (e.g. an integer of more
        than 4300 digits); chained to the original exception.
    """
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise error(f"{path}: cannot read {what} ({exc.strerror or exc})") from exc
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not a {what}: not UTF-8 text (byte {exc.start})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML ({exc})") from exc
    except RecursionError as exc:
        raise error(f"{path}: not a {what}: nested too deeply") from exc
    except ValueError as exc:                 # e.g. an integer of more than 4300 digits
        raise error(f"{path}: not a {what}: {str(exc)[:120]}") from exc


#: The packaged table of the paper's coatings (Sec. 4.B at 1 µm, and Sec. 4.A's idealised
#: surfaces).
TABLE_PATH = resources.files(__package__) / "materials.toml"
#: Its coatings, read once: a read-only mapping of name to :class:`SandfordRobertson`.
PAPER = parse_table(tomllib.loads(TABLE_PATH.read_text(encoding="utf-8")),
                    source=str(TABLE_PATH))
#: Dark gray paint at 1 µm (paper Sec. 4.B): ρd = 0.032, ε = 0.877, b = 0.1, e = 0.17.
DARK_GRAY = PAPER["dark_gray"]
#: Commercial aluminium at 1 µm (paper Sec. 4.B): ρd = 0.047, ε = 0.53, b = 0.1, e = 0.007.
#: Its monostatic F is about 651 sr⁻¹ at normal incidence and 0.04 sr⁻¹ five degrees off.
ALUMINUM = PAPER["aluminum"]
