"""The Returns record refuses what it cannot describe: axes outside COORDINATES (whose
``units`` raised KeyError later) and a second scaling to photoelectrons (as
Waveforms.scaled does)."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.returns import COORDINATES, Returns


def _returns(axes=("range",), **info):
    shape = (2,) + tuple(3 for _ in axes)
    return Returns(np.ones(shape), axes=axes, edges=tuple(np.arange(4.0) for _ in axes),
                   angles_deg=np.zeros(2), view_vectors=np.tile([1.0, 0.0, 0.0], (2, 1)),
                   info=info)


@pytest.mark.parametrize("axes, message", [
    (("bogus",), r"^axes must be a tuple of names from \('range', 'cross_range', "
                 r"'elevation', 'doppler'\); got \('bogus',\)"),
    (("range", 3), r"^axes must be a tuple of names from .*got \('range', 3\)"),
    ("range", r"^axes must be a tuple of names from .*got 'range'"),
    (("range", "range"), r"^axes must be different coordinates; got \('range', 'range'\)"),
])
def test_axes_outside_the_coordinates_are_refused(axes, message):
    with pytest.raises(ParameterError, match=message):
        _returns(axes)


def test_every_coordinate_has_its_units():
    r = _returns(("range", "cross_range", "doppler"))
    assert r.units == ("m", "m", "Hz")
    assert set(COORDINATES) == {"range", "cross_range", "elevation", "doppler"}


def test_photoelectrons_are_not_scaled_to_photoelectrons_again():
    counted = _returns(units="photoelectrons")
    with pytest.raises(ParameterError, match=r"^these returns already count photoelectrons.*"
                                             r"count twice"):
        counted.scaled(10.0)
    volts = counted.scaled(0.5, units="V")                 # another unit is a conversion
    assert volts.info["units"] == "V" and volts.values.max() == 0.5
    relative = _returns(units="length/sr").scaled(1e3)     # relative power to counts
    assert relative.info["units"] == "photoelectrons" and relative.info["scaled_by"] == 1e3


@pytest.mark.parametrize("units", [3, b"photoelectrons"])
def test_units_must_be_a_string_or_none(units):
    with pytest.raises(ParameterError, match=r"^units must be a string or None; got "):
        _returns().scaled(2.0, units=units)
