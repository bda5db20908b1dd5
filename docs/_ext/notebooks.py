"""The example notebooks (``examples/*.ipynb``) as pages of the site, executed at each build.

Each notebook's cells run in order in one namespace, in a scratch folder, as a kernel would
run them; the page holds its Markdown cells as written, its code, and what the code gives
today: printed text, warnings, the value of a cell's last expression, and its figures
(matplotlib figures and the viewer's off-screen pictures, saved as PNG). The notebooks'
stored outputs are not used: a page cannot show a stale result. A cell that raises stops
the build, naming the notebook and the cell.
"""

from __future__ import annotations

import ast
import contextlib
import io
import os
import pathlib
import tempfile
import warnings

HERE = pathlib.Path(__file__).resolve().parents[1]
EXAMPLES = HERE.parent / "examples"
OUT = HERE / "notebooks"


def _code(cell) -> str:
    src = "".join(cell["source"])
    # IPython magics (%matplotlib inline) are not Python
    return "\n".join(line for line in src.splitlines() if not line.lstrip().startswith("%"))


def _picture(value, path) -> bool:
    """Save ``value`` as a PNG at ``path`` if it is a picture: a matplotlib Figure, or an
    image array (the viewer's ``Shown`` off screen)."""
    import matplotlib.image
    import numpy as np
    from matplotlib.figure import Figure

    if isinstance(value, Figure):
        value.savefig(path, dpi=90, bbox_inches="tight")
        return True
    image = getattr(value, "image", None)
    if isinstance(image, np.ndarray) and image.ndim == 3:
        matplotlib.image.imsave(path, image)
        return True
    return False


def _run_cell(source, ns, name):
    """(printed text, warnings, last value) of one cell run in ``ns``."""
    tree = ast.parse(source)
    last = None
    if tree.body and isinstance(tree.body[-1], ast.Expr):
        last = ast.Expression(tree.body.pop().value)
    out = io.StringIO()
    with warnings.catch_warnings(record=True) as seen, contextlib.redirect_stdout(out):
        warnings.simplefilter("always")
        exec(compile(tree, name, "exec"), ns)
        value = eval(compile(last, name, "eval"), ns) if last else None
    said = [f"{type(w.message).__name__}: {w.message}" for w in seen]
    return out.getvalue(), said, value


def page(book_path, folder) -> str:
    """The Markdown page of one notebook, its pictures written into ``folder``."""
    import json

    import matplotlib.pyplot as plt

    book = json.loads(book_path.read_text(encoding="utf-8"))
    stem = book_path.stem
    folder.mkdir(parents=True, exist_ok=True)
    ns = {"__name__": "__main__"}
    lines, pictures = [], 0
    for k, cell in enumerate(book["cells"]):
        if cell["cell_type"] == "markdown":
            lines += ["".join(cell["source"]), ""]
            if k == 0:
                lines += [f"Executed when this site was built, from `examples/{book_path.name}` "
                          f"({{download}}`download the notebook <../../examples/"
                          f"{book_path.name}>`).", ""]
            continue
        if cell["cell_type"] != "code":
            continue
        source = _code(cell)
        lines += ["```python", source.rstrip(), "```", ""]
        try:
            text, said, value = _run_cell(source, ns, f"{book_path.name}, cell {k}")
        except Exception as exc:
            raise RuntimeError(f"{book_path.name}, cell {k} raised {exc!r}") from exc
        shown = [plt.figure(n) for n in plt.get_fignums()]
        values = ([value] if value is not None else []) + [f for f in shown if f is not value]
        if text.strip() or said:
            lines += ["```", *(text.rstrip().splitlines() + said), "```", ""]
        for v in values:
            pictures += 1
            name = f"{stem}_{pictures:02d}.png"
            if _picture(v, folder / name):
                lines += [f"![output of cell {k}]({stem}_files/{name})", ""]
            else:
                pictures -= 1
                lines += ["```", repr(v), "```", ""]
        plt.close("all")
    return "\n".join(lines)


def _write(app):
    import matplotlib

    matplotlib.use("Agg")
    OUT.mkdir(exist_ok=True)
    books = sorted(EXAMPLES.glob("*.ipynb"))
    here = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:
        os.chdir(scratch)
        try:
            for book in books:
                text = page(book, OUT / f"{book.stem}_files")
                (OUT / f"{book.stem}.md").write_text(text, encoding="utf-8")
        finally:
            os.chdir(here)
    index = ["# Notebooks", "",
             "The notebooks in `examples/`, run when this site was built. Open them in "
             "Jupyter to change and rerun them.", "", "```{toctree}", ":maxdepth: 1", "",
             *[b.stem for b in books], "```", ""]
    (OUT / "index.md").write_text("\n".join(index), encoding="utf-8")


def setup(app):
    app.connect("builder-inited", _write)
    return {"parallel_read_safe": True, "version": "1"}
