"""Every numeric flag of simulate, receive and reconstruct given extreme values (issue 29):
0, −1, NaN, ±inf, 1e308, subnormals, a 401-digit integer, text, an empty string. The only
outcomes allowed are exit 0 with a result of finite numbers, or exit 2 with one
"meshladar: error:" line (argparse's usage block aside); never a traceback, a bug report
(exit 1) or a numpy warning."""

from __future__ import annotations

import argparse
import warnings

import numpy as np
import pytest

from meshladar.cli import COMMANDS, main
from meshladar.cli.parser import build_parser
from meshladar.errors import MeshladarWarning
from meshladar.io import load_result

VALUES = ["0", "-1", "nan", "inf", "-inf", "1e308", "1e-320", "5e-324", "1" + "0" * 400,
          "abc", "", "3"]
#: Flags not fuzzed here: --workers starts a local Dask cluster (tests/stream), and the
#: ones that take names, paths or lists.
SKIP = {"--workers", "--scheduler", "--run-dir", "--output", "--materials", "--material",
        "--coating", "--model", "--radiometry", "--mode", "--normals", "--back-faces",
        "--backend", "--sampling", "--filter", "--plot", "--pulse-samples", "--angles-deg",
        "--beam-offset", "--receiver"}


def _flags(command):
    parser = build_parser(COMMANDS)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [a.option_strings[-1] for a in sub.choices[command]._actions
            if a.option_strings and a.type is not None and a.option_strings[-1] not in SKIP]


def _run(argv, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")              # a numpy warning is a defect
        # meshladar's own print as one line (they point at the caller's line, so they are
        # told apart by their class, not by where they are raised)
        warnings.simplefilter("ignore", MeshladarWarning)
        try:
            code = main(argv)
        except SystemExit as exc:                   # argparse's refusal
            code = exc.code
    err = capsys.readouterr().err
    assert code in (0, 2), (argv, code, err)
    assert "Traceback" not in err, err
    if code == 2:
        last = err.strip().splitlines()[-1]
        assert last.startswith("meshladar") and "error:" in last, err
    return code


def _finite(path):
    arrays, _ = load_result(path)
    for name, a in arrays.items():
        if a.dtype.kind == "f":
            assert np.all(np.isfinite(a)), (path, name)


@pytest.mark.parametrize("flag", _flags("simulate"))
def test_simulate_flags(flag, tmp_path, capsys):
    for value in VALUES:
        out = tmp_path / "s.npz"
        argv = ["simulate", "disk", "--model", "mesh", "--views", "2", "--bins", "16",
                "--quiet", "-o", str(out), flag, value]
        if _run(argv, capsys) == 0:
            _finite(out)
            out.unlink()


@pytest.fixture(scope="module")
def sinogram(tmp_path_factory):
    out = tmp_path_factory.mktemp("fuzz") / "sino.npz"
    assert main(["simulate", "disk", "--model", "mesh", "--views", "3", "--bins", "32",
                 "--radiometry", "power", "--quiet", "-o", str(out)]) == 0
    return out


@pytest.mark.parametrize("flag", _flags("receive"))
def test_receive_flags(flag, sinogram, tmp_path, capsys):
    capsys.readouterr()
    for value in VALUES:
        out = tmp_path / "w.npz"
        extra = [] if flag in ("--sample-rate",) else ["--sample-rate", "1e9"]
        if flag in ("--seed", "--speckle-cells", "--background-rate", "--dark-rate",
                    "--excess-noise", "--gain", "--bits", "--full-scale"):
            extra += ["--realisations", "2", "--scale", "1e3"]
        argv = ["receive", str(sinogram), "-o", str(out), *extra, flag, value]
        if _run(argv, capsys) == 0:
            _finite(out)
            out.unlink()


@pytest.mark.parametrize("flag", _flags("reconstruct"))
def test_reconstruct_flags(flag, sinogram, tmp_path, capsys):
    capsys.readouterr()
    for value in VALUES:
        out = tmp_path / "r.png"
        extra = [] if flag == "--size" else ["--size", "16"]
        _run(["reconstruct", str(sinogram), "-o", str(out), *extra, flag, value], capsys)
