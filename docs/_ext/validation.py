"""The validation page, written from the test suite when the site is built: every closed form,
peer comparison and paper finding the tests pin, with the numbers they assert and the
command that reproduces each.

Nothing on the page is typed by hand: for each test of the modules in :data:`SECTIONS` it
shows the test's docstring, its comments and its ``assert`` statements as written (with the
module's named tolerances they use, and their values), and the pytest command that runs it.
A claim that changes in a test changes here at the next build.
"""

from __future__ import annotations

import ast
import pathlib

HERE = pathlib.Path(__file__).resolve().parents[1]
ROOT = HERE.parent
PAGE = HERE / "reference" / "validation.rst"

#: (title, what the tests check, test modules), in the order of the guide
SECTIONS = (
    ("The Sandford–Robertson BRDF and the other models",
     "closed forms, limits and hemispherical quadrature of each model",
     ("tests/brdf/test_brdf.py",)),
    ("Exact range profiles (the analytic model)",
     "bins against adaptive quadrature and closed forms, shadowing, both radiometries",
     ("tests/forward/test_analytic.py",)),
    ("The mesh engine",
     "first hits, packets against embreex, normals, glint sampling, convergence to the "
     "analytic profiles",
     ("tests/forward/test_trace.py", "tests/meshes/test_normals.py",
      "tests/forward/test_glint_sampling.py")),
    ("The sensor, waveforms and noise",
     "the link budget, beams against their closed forms, noise moments against their laws",
     ("tests/values/test_sensor_beams.py", "tests/records/test_waveforms.py")),
    ("Beyond range",
     "Doppler and angle–angle closed forms, the 3-D inversion of a ball",
     ("tests/forward/test_resolved.py", "tests/reconstruct/test_volumes.py")),
    ("Reconstruction",
     "FBP against scikit-image and a uniform disk, exact adjoints, iterative solvers",
     ("tests/reconstruct/test_fbp.py", "tests/reconstruct/test_operators.py",
      "tests/reconstruct/test_iterative.py")),
    ("A peer renderer: Mitsuba 3 and mitransient",
     "received power against a transient path tracer",
     ("tests/studies/test_peer_mitsuba.py",)),
    ("Coating fits and their intervals",
     "profile likelihood against closed forms, the kernel's error, recovery of coatings",
     ("tests/fit/test_profile.py", "tests/fit/test_kernel_error.py",
      "tests/fit/test_fitting.py")),
    ("Beyond one bounce, and laser radar cross sections",
     "the two-bounce integral by quadrature (at infinity, bistatic, from a sensor, both "
     "radiometries), integrating-sphere and mirror-image closed forms, geometric optics of "
     "corner reflectors, cross sections of spheres and plates, Mitsuba 3 + mitransient",
     ("tests/forward/test_bounces.py", "tests/forward/test_bounce_sensor.py",
      "tests/forward/test_mirrors.py", "tests/forward/test_specular_chain.py",
      "tests/forward/test_lrcs.py", "tests/studies/test_peer_bounces.py")),
    ("The paper's findings (Jin & Levine 2009, Figs 5–11)",
     "each finding as a number",
     ("tests/studies/test_paper.py",)),
)


def _constants(tree) -> dict:
    """The module's named numbers: ``NAME = <literal or arithmetic of literals>``."""
    out = {}
    for node in tree.body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if isinstance(t, ast.Name) and t.id.isupper() and node.value is not None:
                    try:
                        value = eval(compile(ast.Expression(node.value), "<c>", "eval"),
                                     {"__builtins__": {}})
                    except Exception:       # noqa: BLE001 - not a plain number
                        continue
                    if isinstance(value, (int, float)) and not isinstance(value, bool):
                        out[t.id] = value
    return out


def _claim(fn, lines) -> list[str]:
    """The test's docstring, comments and asserts, as written."""
    keep = set()
    for node in ast.walk(fn):
        if isinstance(node, ast.Assert):
            keep.update(range(node.lineno, node.end_lineno + 1))
    body_start = fn.body[0].lineno
    for n in range(body_start, fn.end_lineno + 1):
        if lines[n - 1].strip().startswith("#"):
            keep.add(n)
    doc = ast.get_docstring(fn)
    if doc:
        first = fn.body[0]
        keep -= set(range(first.lineno, first.end_lineno + 1))
    out = [f'"""{line}' if i == 0 else line for i, line in enumerate(doc.splitlines())] \
        if doc else []
    if doc:
        out[-1] += '"""'
    indent = None
    for n in sorted(keep):
        line = lines[n - 1]
        if indent is None:
            indent = len(line) - len(line.lstrip())
        out.append(line[min(indent, len(line) - len(line.lstrip())):])
    return out


def _entries(path):
    text = (ROOT / path).read_text(encoding="utf-8")
    tree = ast.parse(text)
    lines = text.splitlines()
    named = _constants(tree)
    for fn in tree.body:
        if not (isinstance(fn, ast.FunctionDef) and fn.name.startswith("test_")):
            continue
        if not any(isinstance(n, ast.Assert) for n in ast.walk(fn)):
            continue
        used = sorted({n.id for n in ast.walk(fn) if isinstance(n, ast.Name)} & set(named))
        yield fn.name, _claim(fn, lines), {k: named[k] for k in used}


def _title(name):
    words = name.removeprefix("test_").replace("_", " ")
    return words[:1].upper() + words[1:]


def page() -> str:
    """The page's reStructuredText."""
    head = "Validation"
    out = [head, "=" * len(head), "",
           "What the test suite pins, written from the tests themselves at each build: for "
           "every test of the modules below, its docstring, comments and assertions as "
           "written, the named tolerances they use, and the command that runs it (in a "
           "clone, after the README's second command). Timings are never asserted.", ""]
    total = 0
    for title, what, modules in SECTIONS:
        out += [title, "-" * len(title), "", what[:1].upper() + what[1:] + ".", ""]
        for module in modules:
            for name, claim, named in _entries(module):
                total += 1
                out += [f"**{_title(name)}**", "",
                        f"``.venv/bin/python -m pytest {module}::{name}``", ""]
                if named:
                    out += ["Named tolerances: " + ", ".join(
                        f"``{k} = {v:g}``" for k, v in named.items()) + ".", ""]
                out += [".. code-block:: python", ""] + \
                    [f"   {line}".rstrip() for line in claim] + [""]
    out += [f"{total} tests in all.", ""]
    return "\n".join(out)


def _write(app):
    text = page()
    PAGE.parent.mkdir(parents=True, exist_ok=True)
    if not PAGE.exists() or PAGE.read_text(encoding="utf-8") != text:
        PAGE.write_text(text, encoding="utf-8")


def setup(app):
    app.connect("builder-inited", _write)
    return {"parallel_read_safe": True, "version": "1"}


if __name__ == "__main__":
    print(page())
