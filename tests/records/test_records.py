"""The records' typed fields (``radiometry``, ``units``) with ``info[...]`` still readable for
one release, files written before the fields existed, and the moved modules' aliases."""

from __future__ import annotations

import ast
import dataclasses
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

import meshladar as ml
from meshladar import io as mlio
from meshladar import plotting
from meshladar.errors import ParameterError
from meshladar.noise import Noise
from meshladar.sinogram import RecordInfo
from meshladar.waveforms import GaussianPulse, Waveforms, receive

ROOT = Path(__file__).resolve().parents[2]


def _sino(**kw):
    return ml.Sinogram(np.arange(6.0).reshape(2, 3), angles_deg=[0.0, 90.0],
                       bin_edges=[0.0, 1.0, 2.0, 3.0], **kw)


def test_typed_fields_from_keywords_or_from_info():
    a = _sino(radiometry="power", units="photoelectrons", info={"rays": 10})
    b = _sino(info={"radiometry": "power", "units": "photoelectrons", "rays": 10})
    for s in (a, b):
        assert s.radiometry == "power" and s.units == "photoelectrons"
        # the old reads keep working: info merges the typed fields with the provenance
        assert s.info["radiometry"] == "power" and s.info.get("units") == "photoelectrons"
        assert s.info["rays"] == 10 and s.provenance == {"rays": 10}
        assert dict(s.info) == {"rays": 10, "radiometry": "power", "units": "photoelectrons"}
    plain = _sino()
    assert plain.radiometry is None and plain.units is None
    assert plain.info.get("radiometry") is None and "radiometry" not in plain.info


def test_info_is_read_only_and_pickles():
    s = _sino(radiometry="paper", info={"rays": 1})
    with pytest.raises(TypeError, match="read-only"):
        s.info["rays"] = 2
    with pytest.raises(TypeError, match="read-only"):
        s.info.update(rays=2)
    assert isinstance(s.info, RecordInfo) and isinstance(s.info, dict)
    back = pickle.loads(pickle.dumps(s))
    assert back.radiometry == "paper" and back.info == s.info
    assert back.values.tobytes() == s.values.tobytes()
    assert json.loads(json.dumps(s.info)) == {"rays": 1, "radiometry": "paper"}


def test_replace_keeps_old_code_working_and_sets_fields_anew():
    s = _sino(radiometry="paper", units="area/sr", info={"rays": 1})
    # old code: a new info dict carries the new value (it wins over the old field)
    t = dataclasses.replace(s, info=dict(s.info, units="dimensionless"))
    assert t.units == "dimensionless" and t.info["units"] == "dimensionless"
    # new code: the field given anew wins over the record's own info
    u = dataclasses.replace(s, units="photoelectrons")
    assert u.units == "photoelectrons" and u.info["units"] == "photoelectrons"
    assert u.radiometry == "paper" and u.provenance == {"rays": 1}


def test_bad_typed_fields_are_refused():
    with pytest.raises(ParameterError, match="radiometry"):
        _sino(radiometry=3)
    with pytest.raises(ParameterError, match="info must be a dict"):
        _sino(info=[("radiometry", "power")])


def test_a_file_written_before_the_fields_loads_and_new_files_read_the_same(tmp_path):
    # the format of files written before the change: radiometry and units inside meta.info
    old = tmp_path / "old.npz"
    mlio.save_result(old, {"values": np.ones((2, 3)), "angles_deg": np.array([0.0, 90.0]),
                           "bin_edges": np.array([0.0, 1.0, 2.0, 3.0])},
                     {"kind": "sinogram", "model": "mesh", "scene": None, "params": {},
                      "info": {"radiometry": "power", "units": "photoelectrons",
                               "rays": 7}})
    s, _ = mlio.load_sinogram(old)
    assert s.radiometry == "power" and s.units == "photoelectrons" and s.info["rays"] == 7
    # a new file keeps them where old readers look
    new = tmp_path / "new.npz"
    mlio.save_sinogram(new, s)
    _, meta = mlio.load_result(new)
    assert meta["info"] == {"radiometry": "power", "units": "photoelectrons", "rays": 7}
    back, _ = mlio.load_sinogram(new)
    assert back.radiometry == "power" and back.values.tobytes() == s.values.tobytes()


def test_waveforms_carry_the_sinograms_typed_fields(tmp_path):
    sino = _sino(radiometry="power", units="photoelectrons", info={"rays": 3})
    waves = receive(sino, sample_rate=2e9, pulse=GaussianPulse(1e-9))
    assert waves.radiometry == "power" and waves.units == "photoelectrons"
    assert waves.info["radiometry"] == "power" and waves.info["units"] == "photoelectrons"
    assert waves.info["source_info"]["rays"] == 3
    scaled = waves.scaled(2.0, units="counts")
    assert scaled.units == "counts" and scaled.info["scaled_by"] == 2.0
    assert scaled.radiometry == "power"
    # a waveform without them still shows both keys in info (as before: None)
    bare = receive(_sino(), sample_rate=2e9)
    assert bare.info["units"] is None and bare.units is None
    path = tmp_path / "w.npz"
    mlio.save_waveforms(path, waves)
    back, _, meta = mlio.load_waveforms(path)
    assert back.units == "photoelectrons" and meta["info"]["radiometry"] == "power"
    assert back.values.tobytes() == waves.values.tobytes()


def test_plot_goes_through_the_one_door(monkeypatch):
    seen = []
    monkeypatch.setattr(plotting, "plot", lambda record, **opts: seen.append(
        (type(record).__name__, sorted(opts))) or "figure")
    sino = _sino(units="photoelectrons")
    assert sino.plot(log=True) == "figure"
    waves = receive(sino, sample_rate=2e9)
    assert waves.plot(noise=Noise(), realisations=2) == "figure"
    assert seen == [("Sinogram", ["log"]), ("Waveforms", ["noise", "realisations", "views"])]


def test_no_import_circle_and_the_old_modules_are_aliases():
    tree = ast.parse((ROOT / "meshladar" / "_validate.py").read_text(encoding="utf-8"))
    imported = {getattr(n, "module", None) for n in ast.walk(tree)
                if isinstance(n, ast.ImportFrom)}
    assert "sinogram" not in imported
    from meshladar import waveforms as receiver
    from meshladar import io as results

    assert receiver.Noise is Noise and receiver.Waveforms is Waveforms
    assert receiver.receive is receive and results.save_sinogram is mlio.save_sinogram
    from meshladar._validate import check_sinogram

    with pytest.raises(ParameterError, match="Sinogram"):
        check_sinogram("sino", np.ones((2, 3)))
    assert check_sinogram("sino", _sino()) is not None


def test_the_foundations_version_is_the_packages():
    from meshladar._version import __version__

    assert __version__ == ml.__version__
