"""The phantom library: the paper's phantoms and coatings as small declarative specs.

Installed as ``meshladar.phantoms``. For now it holds the coating table
(``materials.toml``); the phantom specs arrive with the analytic forward model.
"""

from __future__ import annotations

from importlib import resources

__all__ = ["materials", "MATERIALS_TOML"]

#: Path of the packaged coating table.
MATERIALS_TOML = resources.files(__name__) / "materials.toml"


def materials():
    """The packaged coating table as a read-only mapping of name to SandfordRobertson.

    Note that the paper's idealised diffuse surfaces are not all energy-conserving; the
    packaged table holds only entries that are (b = 0.99 with rho_d = 1 is made in code).
    """
    from meshladar.materials import load_table

    with resources.as_file(MATERIALS_TOML) as path:
        return load_table(path)
