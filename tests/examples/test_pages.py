"""Every code example in README.md and in the user guide's pages (``docs/guide/*.md``) runs,
as written, in the test suite.

Conventions (what runs, and how):

* Fenced blocks are found outside other blocks. A block belongs to a section: in the
  README the ``##`` section above it, in a guide page the page itself (its ``#`` title; its
  ``##`` subsections share it). Each block is one test case named by its page, section and
  the line of its opening fence (``guide-tour-a-tour-L6``), so a failure points at the text.
  ``:::`` fences are MyST directives (images, includes), not code.
* ```` ```python ```` blocks run in page order in one namespace per section (the
  phantoms subsection uses the Scenes page's ``ml``). Running one block alone first runs
  the blocks above it in its section. The code is compiled as written, never rewritten.
  A page starts from its own first block: nothing is carried from another page (the
  tour's mesh files apart, below).
* ```` ```bash ```` blocks are commands: each line (with its ``\\`` continuations) that
  starts with ``meshladar``, ``python`` or ``.venv/bin/`` runs through bash and must exit
  0; ``python``, ``meshladar`` and ``.venv/bin/`` mean this interpreter's. Set-up lines (``pip install``,
  ``python3 -m venv``, ``git clone``) are left to CI, which runs them itself. Comment lines
  are skipped.
* Plain ```` ``` ```` blocks (no language) are synopses and listings, never run.
* Every block runs in a fresh scratch folder holding the mesh files the tour makes
  (``part.stl``, ``probe.glb``), made by the tour's own first command; a page that uses
  them says so and links the tour.
* Warnings are errors (as in the whole suite), except a warning the text says the block
  gives: :data:`WARNS` names it, and the block must give it.
* Blocks over ~5 s are marked slow in :data:`SLOW`.
"""

from __future__ import annotations

import gc
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
#: the pages whose examples run: the README, then the guide's pages
PAGES = [README] + sorted((ROOT / "docs" / "guide").glob("*.md"))

#: Blocks the README says warn: (section start, ordinal of the block in its section) ->
#: the warning class name the block must give (and may give, alone of all warnings).
WARNS = {
    ("BRDFs and coatings", 0): "EnergyConservationWarning",
}

#: Blocks over ~5 s (section start, ordinal): run by the full suite, left out of the fast one.
SLOW = {
    ("In ten lines", 0), ("A tour", 0), ("Getting started", 1), ("Getting started", 2),
    ("Reconstruction", 2), ("Reconstruction", 3), ("Meshes", 0), ("The sensor", 0),
    ("The sensor", 1), ("The sensor", 2), ("The sensor", 3), ("Beyond range", 2),
    ("Long runs", 0), ("Long runs", 1), ("Accuracy", 1), ("Command line", 1),
}

SETUP = ("pip install", "python3 -m venv", "git clone")
COMMAND = re.compile(r"^(meshladar|python|\.venv/bin/)")


@dataclass(frozen=True)
class Block:
    lang: str
    line: int          # 1-based line of the opening fence
    section: str       # the README's ## heading ("(top)" before the first), a page's title
    ordinal: int       # the block's place among its section's blocks (0, 1, ...)
    code: str
    page: str = "README.md"     # relative to the repository

    @property
    def id(self):
        words = re.findall(r"[a-z0-9]+", self.section.lower())
        where = "" if self.page == "README.md" else \
            "-".join(pathlib.PurePosixPath(self.page).with_suffix("").parts[1:]) + "-"
        return f"{where}{'-'.join(words[:3]) or 'top'}-L{self.line}"

    @property
    def where(self):
        return f"{self.page}:{self.line}"

    def key_in(self, table):
        return next((v for (s, i), v in _items(table) if self.section.startswith(s)
                     and i == self.ordinal), None)


def _items(table):
    return table.items() if isinstance(table, dict) else ((k, True) for k in table)


def blocks(text=None, page="README.md"):
    """Every fenced block of a page (the README unless ``text`` is given), in order."""
    if text is None:
        text = (ROOT / page).read_text(encoding="utf-8")
    heading = "## " if page == "README.md" else "# "
    out, section, fence, counts = [], "(top)", None, {}
    for n, line in enumerate(text.splitlines(), 1):
        if fence is None:
            m = re.match(r"^```(\w*)\s*$", line)
            if m:
                fence, body = (m.group(1), n), []
            elif line.startswith(heading):
                section = line[len(heading):].strip()
            continue
        if line.startswith("```"):
            lang, start = fence
            counts[section] = counts.get(section, -1) + 1
            out.append(Block(lang, start, section, counts[section], "\n".join(body) + "\n",
                             page))
            fence = None
        else:
            body.append(line)
    assert fence is None, f"{page}: the block opened at line {fence[1]} is not closed"
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


BLOCKS = [b for p in PAGES for b in blocks(page=p.relative_to(ROOT).as_posix())]
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


def test_pages_have_blocks():
    """The parser sees the README's and the guide's examples (a parser that saw none would
    pass all)."""
    assert len(PYTHON) >= 15 and len(BASH) >= 3
    assert {"In ten lines", "Reconstruction", "Getting started"} <= {b.section for b in PYTHON}
    assert {b.page for b in PYTHON} >= {"README.md", "docs/guide/getting_started.md",
                                        "docs/guide/scenes.md"}
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
    # a guide page: its title is the section, its ## subsections share it; ::: is no fence
    page = blocks("# T\n```python\nx = 1\n```\n## Sub\n:::{image} a.png\n:::\n"
                  "```python\ny = x\n```\n", page="docs/guide/t.md")
    assert [(b.section, b.ordinal) for b in page] == [("T", 0), ("T", 1)]
    assert commands(found[1]) == ["meshladar simulate a --views 3 -o a.npz"]


# ---- python blocks --------------------------------------------------------------------

_NAMESPACES: dict = {}


def _run_python(block):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        exec(compile(block.code, block.where, "exec"), _namespace_for(block))
    want = block.key_in(WARNS)
    names = sorted({type(w.message).__name__ for w in seen})
    unexpected = [f"{type(w.message).__name__}: {w.message}" for w in seen
                  if type(w.message).__name__ != want]
    assert not unexpected, f"{block.where} warns: {unexpected}"
    if want:
        assert want in names, f"{block.where} should warn {want} (the text says so)"


def _namespace_for(block):
    """The section's namespace with every earlier block of the section run in it."""
    key = (block.page, block.section)
    if key not in _NAMESPACES:
        # a script's name: a block's `if __name__ == "__main__":` runs, as in the user's
        # script (where Dask's and --jobs' worker processes import it without running it)
        _NAMESPACES[key] = [{"__name__": "__main__"}, 0]
    ns, done = _NAMESPACES[key]
    earlier = [b for b in PYTHON if (b.page, b.section) == key and b.ordinal < block.ordinal]
    for b in earlier[done:]:
        _NAMESPACES[key][1] += 1
        try:
            exec(compile(b.code, b.where, "exec"), ns)
        except Exception as exc:        # noqa: BLE001 - names the earlier block
            pytest.fail(f"an earlier block of the section ({b.where}) failed: {exc!r}")
    _NAMESPACES[key][1] = max(_NAMESPACES[key][1], block.ordinal + 1)
    return ns


@pytest.fixture(scope="module", autouse=True)
def _release_namespaces():
    """Drop the pages' namespaces (a viewer's plotter among them) while pyvista and VTK are
    still loaded: collected at interpreter exit, a plotter prints "Exception ignored"."""
    yield
    _NAMESPACES.clear()
    if "pyvista" in sys.modules:
        sys.modules["pyvista"].close_all()
    gc.collect()


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
        assert res.returncode == 0, (f"{block.where}: `{cmd}` exited "
                                     f"{res.returncode}:\n{res.stderr[-3000:]}")
