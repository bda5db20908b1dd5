"""The reconstruction study refuses an unknown setting, method or spacing before any work,
naming the value and the valid choices (an unknown method used to run as "tv" under its
own label, a string of methods letter by letter, an unknown setting raised KeyError)."""

from __future__ import annotations

import pytest

from meshladar.errors import ParameterError
from meshladar.studies import reconstruction as study

CHOICES = r"\('fbp', 'fbp_log', 'fbp_clip', 'sirt', 'sirt_glint', 'sart', 'cgls', 'tv', 'compensated'\)"


def _no_work():
    raise AssertionError("the study started work before checking its arguments")


@pytest.mark.parametrize("kwargs, message", [
    (dict(setting="quik"), r"^setting must be one of \('quick', 'full'\); got 'quik'$"),
    (dict(setting=None), r"^setting must be one of \('quick', 'full'\); got None$"),
    (dict(methods=["fbp", "fbpp"]), rf"^methods\[1\] must be one of {CHOICES}; got 'fbpp'$"),
    (dict(methods="fbp"), r"^methods must be a non-empty list or tuple; got 'fbp'$"),
    (dict(methods=[]), r"^methods must be a non-empty list or tuple; got \[\]$"),
    (dict(spacings=[5.0, 0.0]), r"^spacings\[1\] must be in \(0, inf\); got 0\.0$"),
    (dict(spacings=[float("nan")]), r"^spacings\[0\] must be finite and in \(0, inf\); "
                                    r"got nan$"),
    (dict(spacings=5.0), r"^spacings must be a non-empty list or tuple; got 5\.0$"),
])
def test_a_bad_setting_method_or_spacing_is_refused_before_any_work(monkeypatch, kwargs,
                                                                     message):
    monkeypatch.setattr(study, "_phantoms", _no_work)
    with pytest.raises(ParameterError, match=message):
        study.run(**kwargs)


def test_good_arguments_reach_the_work(monkeypatch):
    monkeypatch.setattr(study, "_phantoms", _no_work)
    with pytest.raises(AssertionError, match="started work"):
        study.run("full", methods=("fbp", "compensated"), spacings=(20.0,))
