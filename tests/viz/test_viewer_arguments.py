"""show_volume refuses bad arguments with ParameterError (still a ValueError, so callers
that catch ValueError keep working), before pyvista is imported or anything is drawn:
pyvista's import is replaced by one that fails the test."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.images import Volume
from meshladar.viz import _reconstruction_view, viewer

ZS = np.linspace(-0.5, 0.5, 4)
IMAGES = [ml.Image(np.ones((8, 8)), 1.0) for _ in ZS]
VOLUME = Volume(np.ones((4, 8, 8)), x=np.linspace(-0.5, 0.5, 8), y=np.linspace(-0.5, 0.5, 8),
                z=ZS)


@pytest.fixture(autouse=True)
def no_pyvista(monkeypatch):
    def load():
        raise AssertionError("pyvista was loaded before the arguments were checked")

    monkeypatch.setattr(_reconstruction_view, "_pyvista", load)


@pytest.mark.parametrize("args, options, message", [
    ((IMAGES, ZS), {"render": "fog"},
     r"^render must be one of \('iso', 'volume'\); got 'fog'"),
    ((IMAGES, ZS), {"iso": float("nan")}, r"^iso must be finite"),
    ((VOLUME, [0.0, 1.0]), {}, r"^a Volume carries its own z; do not give zs; got zs="),
    ((IMAGES,), {}, r"^a stack of images needs zs, one height per image; got zs=None"),
    ((IMAGES[:1], ZS[:1]), {}, r"^images and zs must have the same length >= 2; got 1 "
                               r"images and zs of shape \(1,\)"),
    ((IMAGES, ZS[:3]), {}, r"^images and zs must have the same length >= 2; got 4 images"),
    ((IMAGES, np.r_[ZS[:-1], 9.0]), {}, r"^zs must be increasing and evenly spaced; got "),
    ((IMAGES, np.r_[ZS[:-1], np.nan]), {}, r"^zs must be finite; got nan at index \(3,\)"),
    ((np.ones((4, 8, 8)), ZS), {}, r"^images must be a Volume or a list or tuple of Images"),
])
def test_bad_arguments_are_parameter_errors_before_pyvista(args, options, message):
    with pytest.raises(ParameterError, match=message) as caught:
        viewer.show_volume(*args, off_screen=True, **options)
    assert isinstance(caught.value, ValueError)
