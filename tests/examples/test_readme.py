"""Every code example in README.md runs, as written, in the test suite.

Conventions (what runs, and how):

* Fenced blocks are found outside other blocks; a block belongs to the ``##`` section (and
  ``###`` subsection) above it. Each block is one test case named by its section and the
  README line of its opening fence (``tour-L47``), so a failure points at the text.
* ```` ```python ```` blocks run in README order in one namespace per ``##`` section (its
  subsections share it: the phantoms subsection uses the Scenes section's ``ml``). Running
  one block alone first runs the blocks above it in its section. The code is compiled as
  written, never rewritten. What the reader holds at a section's start from earlier
  sections is that section's :data:`PRELUDES` entry, stated here in the open.
* ```` ```bash ```` blocks are commands: each line (with its ``\\`` continuations) that
  starts with ``meshladar``, ``python`` or ``.venv/bin/`` runs through bash and must exit
  0; ``python``, ``meshladar`` and ``.venv/bin/`` mean this interpreter's. Set-up lines (``pip install``,
  ``python3 -m venv``, ``git clone``) are left to CI, which runs them itself. Comment lines
  are skipped.
* Plain ```` ``` ```` blocks (no language) are synopses and listings, never run.
* Every block runs in a fresh scratch folder holding the mesh files the tour makes
  (``part.stl``, ``probe.glb``), made by the tour's own first command.
* Warnings are errors (as in the whole suite), except a warning the README says the block
  gives: :data:`WARNS` names it, and the block must give it.
* Blocks over ~5 s are marked slow in :data:`SLOW`.
"""

from __future__ import annotations

import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import warnings
from dataclasses import dataclass

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
README = ROOT / "README.md"

#: Names a section's examples use that an earlier section defined (or that stand for the
#: reader's own data), as the reader has them at that point. Keyed by the section title's
#: start; the README's own sections make their own names where they can.
PRELUDES = {
    # the Scenes section's sino (the paper's pair), points and radii to sample at, and the
    # pair's coatings with each pixel's coating (left of x = 0.05: gray; right: aluminium)
    "Reconstruction": (
        "import numpy as np, meshladar as ml\n"
        "from meshladar.materials import DARK_GRAY, ALUMINUM\n"
        "sino = ml.simulate(ml.phantoms.scene('disk_pair', large=DARK_GRAY, small=ALUMINUM),"
        " ml.Ladar.paper())\n"
        "points = np.array([[0.1, 0.0], [0.4, 0.3]]); radii = np.array([0.2, 0.4])\n"
        "coating, gray, aluminium = DARK_GRAY, DARK_GRAY, ALUMINUM\n"
        "labels = np.broadcast_to((np.linspace(-1, 1, 512) > 0.05).astype(int), (512, 512))\n"
    ),
    # the tour's sphere as `part`, views about z, and cross-range and Doppler bin edges
    "Beyond range": (
        "import numpy as np, meshladar as ml\n"
        "part = ml.Scene.from_mesh('part.stl', material=ml.materials.DARK_GRAY)\n"
        "ladar = ml.Ladar.covering(part, n_bins=64, angles_deg=np.arange(0, 360, 30.0))\n"
        "e = np.linspace(-0.6, 0.6, 33); f = np.linspace(-2e5, 2e5, 33)\n"
    ),
    # the paper's pair, 72 views of 64 bins, and Poisson counts of 1e5 in the brightest bin
    "Coatings from ladar data": (
        "import numpy as np, meshladar as ml\n"
        "scene = ml.phantoms.scene('disk_pair', large=ml.materials.DARK_GRAY,"
        " small=ml.materials.ALUMINUM)\n"
        "ladar = ml.Ladar(angles_deg=np.arange(0, 360, 5.0),"
        " bin_edges=np.linspace(-0.8, 0.8, 65))\n"
        "exact = ml.simulate(scene, ladar); k = 1e5 / exact.values.max()\n"
        "measured = ml.Sinogram(np.random.default_rng(0).poisson(k * exact.values) / k,"
        " angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges)\n"
    ),
    # the mixed disk pair at 10° views, the set-up the text says tol is tested on
    "Accuracy": (
        "import numpy as np, meshladar as ml\n"
        "scene = ml.phantoms.scene('disk_pair', large=ml.materials.DARK_GRAY,"
        " small=ml.materials.ALUMINUM)\n"
        "ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 10.0))\n"
    ),
}

#: Blocks the README says warn: (section start, ordinal of the block in its section) ->
#: the warning class name the block must give (and may give, alone of all warnings).
WARNS = {
    ("The Sandford", 0): "EnergyConservationWarning",
}

#: Blocks over ~5 s (section start, ordinal): run by the full suite, left out of the fast one.
SLOW = {
    ("(top)", 1), ("A tour", 0), ("Reconstruction", 1), ("Reconstruction", 2),
    ("Meshes", 0), ("The sensor", 0), ("The sensor", 1), ("The sensor", 2), ("The sensor", 3),
    ("Beyond range", 1), ("Long runs", 0), ("Long runs", 1), ("Accuracy", 0),
}

SETUP = ("pip install", "python3 -m venv", "git clone")
COMMAND = re.compile(r"^(meshladar|python|\.venv/bin/)")


@dataclass(frozen=True)
class Block:
    lang: str
    line: int          # 1-based line of the opening fence
    section: str       # the ## heading ("(top)" before the first)
    ordinal: int       # the block's place among its section's blocks (0, 1, ...)
    code: str

    @property
    def id(self):
        words = re.findall(r"[a-z0-9]+", self.section.lower())
        return f"{'-'.join(words[:3]) or 'top'}-L{self.line}"

    def key_in(self, table):
        return next((v for (s, i), v in _items(table) if self.section.startswith(s)
                     and i == self.ordinal), None)


def _items(table):
    return table.items() if isinstance(table, dict) else ((k, True) for k in table)


def blocks(text=None):
    """Every fenced block of the README, in order."""
    lines = (README.read_text(encoding="utf-8") if text is None else text).splitlines()
    out, section, fence, counts = [], "(top)", None, {}
    for n, line in enumerate(lines, 1):
        if fence is None:
            m = re.match(r"^```(\w*)\s*$", line)
            if m:
                fence, body = (m.group(1), n), []
            elif line.startswith("## "):
                section = line[3:].strip()
            continue
        if line.startswith("```"):
            lang, start = fence
            counts[section] = counts.get(section, -1) + 1
            out.append(Block(lang, start, section, counts[section], "\n".join(body) + "\n"))
            fence = None
        else:
            body.append(line)
    assert fence is None, f"README.md: the block opened at line {fence[1]} is not closed"
    return out


def commands(block):
    """The runnable command lines of a bash block: continuations joined, set-up and
    comments left out."""
    joined, cur = [], ""
    for line in block.code.splitlines():
        cur += line.strip() if cur else line.rstrip()
        if cur.endswith("\\"):
            cur = cur[:-1].rstrip() + " "
            continue
        joined.append(cur.strip())
        cur = ""
    return [c for c in joined if COMMAND.match(c) and not any(s in c for s in SETUP)]


BLOCKS = blocks()
PYTHON = [b for b in BLOCKS if b.lang == "python"]
BASH = [b for b in BLOCKS if b.lang == "bash"]
TOUR_MESHES = next(c for b in BASH if b.section == "A tour" for c in commands(b)
                   if "probe.glb" in c and c.startswith((".venv/bin/python", "python")))


def _param(b):
    marks = [pytest.mark.slow] if b.key_in(SLOW) else []
    return pytest.param(b, id=b.id, marks=marks)


def _bash(cmd, cwd, bindir, timeout=1800):
    env = dict(os.environ, PATH=f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}",
               MPLBACKEND="Agg")
    cmd = cmd.replace(".venv/bin/", f"{shlex.quote(str(bindir))}/")
    return subprocess.run(["bash", "-c", cmd], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)


@pytest.fixture(scope="session")
def bindir(tmp_path_factory):
    """``python`` and ``meshladar`` as this interpreter runs them (an installed script's
    ``#!`` may name another environment's interpreter)."""
    where = tmp_path_factory.mktemp("bin")
    for name, run in (("python", ""), ("meshladar", " -m meshladar")):
        (where / name).write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)}{run} "$@"\n')
        (where / name).chmod(0o755)
    return where


@pytest.fixture(scope="session")
def tour_files(tmp_path_factory, bindir):
    """The mesh files the tour's first command makes (part.stl, probe.glb)."""
    where = tmp_path_factory.mktemp("tour-files")
    res = _bash(TOUR_MESHES, where, bindir)
    assert res.returncode == 0, f"the tour's mesh command failed:\n{res.stderr[-3000:]}"
    return where


@pytest.fixture
def scratch(tmp_path, tour_files, monkeypatch):
    for f in tour_files.iterdir():
        shutil.copy(f, tmp_path / f.name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_readme_has_blocks():
    """The parser sees the README's examples (a parser that saw none would pass all)."""
    assert len(PYTHON) >= 15 and len(BASH) >= 3
    assert {"(top)", "Reconstruction"} <= {b.section for b in PYTHON}
    assert any("meshladar simulate" in c for b in BASH for c in commands(b))
    for table in (SLOW, WARNS):         # every entry names a block that exists
        for section, ordinal in table:
            assert any(b.section.startswith(section) and b.ordinal == ordinal
                       and b.lang in ("python", "bash") for b in BLOCKS), (section, ordinal)


def test_synopsis_is_not_run():
    """The convention: plain fences are listings; a bash block's set-up and comment
    lines are not commands."""
    text = ("## S\n```\nmeshladar simulate SCENE [--smooth N]\n```\n"
            "```bash\n# a comment\npython3 -m venv .venv && .venv/bin/pip install -e .\n"
            "meshladar simulate a \\\n    --views 3 -o a.npz\n```\n")
    found = blocks(text)
    assert [b.lang for b in found] == ["", "bash"]
    assert commands(found[1]) == ["meshladar simulate a --views 3 -o a.npz"]


# ---- python blocks --------------------------------------------------------------------

_NAMESPACES: dict = {}


def _run_python(block):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        exec(compile(block.code, f"README.md:{block.line}", "exec"), _namespace_for(block))
    want = block.key_in(WARNS)
    names = sorted({type(w.message).__name__ for w in seen})
    unexpected = [f"{type(w.message).__name__}: {w.message}" for w in seen
                  if type(w.message).__name__ != want]
    assert not unexpected, f"README.md:{block.line} warns: {unexpected}"
    if want:
        assert want in names, f"README.md:{block.line} should warn {want} (the text says so)"


def _namespace_for(block):
    """The section's namespace with every earlier block of the section run in it."""
    key = block.section
    if key not in _NAMESPACES:
        ns = {"__name__": "__readme__"}
        prelude = next((p for s, p in PRELUDES.items() if key.startswith(s)), "")
        exec(compile(prelude, f"prelude of {key!r}", "exec"), ns)
        _NAMESPACES[key] = [ns, 0]
    ns, done = _NAMESPACES[key]
    earlier = [b for b in PYTHON if b.section == key and b.ordinal < block.ordinal]
    for b in earlier[done:]:
        _NAMESPACES[key][1] += 1
        try:
            exec(compile(b.code, f"README.md:{b.line}", "exec"), ns)
        except Exception as exc:        # noqa: BLE001 - names the earlier block
            pytest.fail(f"an earlier block of the section (README.md:{b.line}) failed: {exc!r}")
    _NAMESPACES[key][1] = max(_NAMESPACES[key][1], block.ordinal + 1)
    return ns


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")


@pytest.mark.parametrize("block", [_param(b) for b in PYTHON])
def test_python_block(block, scratch):
    _run_python(block)


# ---- bash blocks ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def rendering():
    sys.path.insert(0, str(ROOT / "tests"))
    from _rendering import _SMOKE

    res = subprocess.run([sys.executable, "-c", _SMOKE], capture_output=True, timeout=300)
    if res.returncode:
        if os.environ.get("CI"):
            pytest.fail("off-screen rendering unavailable (see _rendering)")
        pytest.skip("off-screen rendering unavailable (see _rendering)")


@pytest.mark.parametrize("block", [_param(b) for b in BASH])
def test_bash_block(block, scratch, bindir, request):
    cmds = commands(block)
    if any(c.startswith("meshladar view") for c in cmds):
        request.getfixturevalue("rendering")
    for cmd in cmds:
        res = _bash(cmd, scratch, bindir)
        assert res.returncode == 0, (f"README.md:{block.line}: `{cmd}` exited "
                                     f"{res.returncode}:\n{res.stderr[-3000:]}")
