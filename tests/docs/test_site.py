"""The documentation site builds offline from the repository, warnings as errors and every
cross-reference checked (``sphinx-build -W -n``), with its gallery executed; its command-line
reference holds every option ``--help`` shows and its API reference every public module."""

from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys

import pytest

import meshladar
from meshladar.cli import COMMANDS
from meshladar.cli.parser import build_parser

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-n", "--keep-going", "-q",
                           "-b", "html", "-d", str(out / "doctrees"), str(ROOT / "docs"),
                           str(out / "html")], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-6000:]
    return out / "html"


@pytest.mark.slow
def test_the_cli_reference_is_the_parsers(site):
    """Every option of every command, as ``--help`` has it, is on the page."""
    page = (site / "reference" / "cli.html").read_text(encoding="utf-8")
    parser = build_parser(COMMANDS)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == list(COMMANDS)
    for name, command in sub.choices.items():
        assert f"meshladar {name}" in page
        for action in command._actions:
            for flag in action.option_strings:
                assert flag in page, (name, flag)


@pytest.mark.slow
def test_the_api_reference_has_every_public_module(site):
    index = (site / "reference" / "api" / "index.html").read_text(encoding="utf-8")
    for name in meshladar._SUBMODULES:
        assert (site / "reference" / "api" / f"{name}.html").exists(), name
        assert f"meshladar.{name}" in index
    fbp = (site / "reference" / "api" / "reconstruct.html").read_text(encoding="utf-8")
    assert 'id="meshladar.reconstruct.fbp"' in fbp and "Parameters" in fbp


@pytest.mark.slow
def test_the_gallery_ran_and_drew(site):
    """Each gallery script ran at build time and its figure is on its page."""
    scripts = sorted((ROOT / "docs" / "gallery").glob("plot_*.py"))
    assert len(scripts) >= 11
    for script in scripts:
        page = (site / "auto_gallery" / f"{script.stem}.html").read_text(encoding="utf-8")
        assert f"sphx_glr_{script.stem}_001.png" in page, script.name
        assert (site / "_images" / f"sphx_glr_{script.stem}_001.png").stat().st_size > 10_000


def _validation():
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        import validation
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    return validation


def test_the_validation_page_is_written_from_the_tests():
    """The page quotes the paper tests' assertions as written and the command for each; a
    test's changed tolerance would change the page (no number is typed by hand)."""
    validation = _validation()
    text = validation.page()
    source = (ROOT / "tests" / "studies" / "test_paper.py").read_text(encoding="utf-8")
    line = next(s.strip() for s in source.splitlines() if "disk_b0.99.darkening\"] < -" in s)
    assert line in text
    assert ".venv/bin/python -m pytest tests/studies/test_paper.py::" \
           "test_glancing_loss_darkens_the_interior_boundary" in text
    assert "``G_RTOL = 1e-12``" in text            # a named tolerance, with its value
    for _title, _what, modules in validation.SECTIONS:
        for module in modules:
            assert (ROOT / module).exists(), module
    total = int(text.rsplit(" tests in all", 1)[0].rsplit("\n", 1)[-1])
    assert total >= 150


@pytest.mark.slow
def test_the_validation_page_is_built(site):
    page = (site / "reference" / "validation.html").read_text(encoding="utf-8")
    assert "test_lambertian_disk_is_not_darkened" in page and "Named tolerances" in page


@pytest.mark.slow
def test_the_notebooks_ran_at_build_time(site):
    """Each notebook in examples/ is a page, its figures drawn by this build (the stored
    outputs are not used) and its download offered."""
    books = sorted((ROOT / "examples").glob("*.ipynb"))
    assert len(books) >= 3
    for book in books:
        page = (site / "notebooks" / f"{book.stem}.html").read_text(encoding="utf-8")
        assert f"{book.stem}_01.png" in page and book.name in page, book.name
        assert (site / "_images" / f"{book.stem}_01.png").stat().st_size > 10_000
