"""Re-execute the example notebooks in place, so their stored outputs are today's (what
tests/examples/test_notebooks.py checks), with PNG outputs quantised to 256 colours (a third of the
bytes; the figures look the same).

    pip install nbclient ipykernel    # authoring only: not a dependency of meshladar
    python examples/execute.py [NAME.ipynb ...]

Edit a notebook in Jupyter (or as JSON), then run this; commit the result.
"""

from __future__ import annotations

import base64
import io
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent


def _shrink(book):
    from PIL import Image

    for cell in book.cells:
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            if "image/png" in data:
                im = Image.open(io.BytesIO(base64.b64decode(data["image/png"])))
                buf = io.BytesIO()
                im.convert("RGB").quantize(256).save(buf, format="png", optimize=True)
                data["image/png"] = base64.b64encode(buf.getvalue()).decode()


def main(names):
    import nbformat
    from nbclient import NotebookClient

    paths = [HERE / n for n in names] or sorted(HERE.glob("*.ipynb"))
    for path in paths:
        book = nbformat.read(path, as_version=4)
        NotebookClient(book, timeout=600, kernel_name="python3",
                       resources={"metadata": {"path": str(HERE)}}).execute()
        _shrink(book)
        nbformat.write(book, path)
        print(f"executed {path.name}")


if __name__ == "__main__":
    main(sys.argv[1:])
