"""examples/notebook.ipynb runs as Jupyter runs it (its code cells in order, in one namespace,
from the notebook's folder, the value of each cell's last expression displayed), and what it
shows is what a notebook user reads: short reprs, PNG images of the size rendered."""

import ast
import json
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "examples" / "notebook.ipynb"


def run_cells(path: Path) -> list:
    """Each code cell's displayed value: (cell index, the value), as IPython displays the value of
    a cell's last statement when it is an expression."""
    notebook = json.loads(path.read_text())
    assert notebook["nbformat"] == 4
    namespace, shown = {"__name__": "__main__"}, []
    for k, cell in enumerate(notebook["cells"]):
        if cell["cell_type"] != "code":
            continue
        assert cell["outputs"] == [] and cell["execution_count"] is None    # kept without outputs
        tree = ast.parse("".join(cell["source"]))
        last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
        exec(compile(tree, f"cell {k}", "exec"), namespace)
        if last is not None:
            shown.append((k, eval(compile(ast.Expression(last.value), f"cell {k}", "eval"), namespace)))
    return shown


def test_the_example_notebook_runs_and_shows_short_reprs_and_images(monkeypatch):
    monkeypatch.chdir(NOTEBOOK.parent)
    shown = run_cells(NOTEBOOK)
    images = [value for _, value in shown if hasattr(value, "_repr_png_")]
    texts = [repr(value) for _, value in shown if not hasattr(value, "_repr_png_")]
    assert len(images) == 3 and len(texts) == 5
    for text in texts:      # one line each, however large the arrays behind it
        assert "\n" not in text and len(text) < 400 and "array(" not in text, text
    assert texts[0].startswith("<Scene 'cornell-box': 0 spheres, 6 meshes") and "bounds (0, 0, 0) to" in texts[0]
    decoded = [cv2.imdecode(np.frombuffer(image._repr_png_(), np.uint8), cv2.IMREAD_COLOR) for image in images]
    assert [d.shape for d in decoded] == [(128, 128, 3), (128, 128, 3), (96, 96, 3)]
    # the wall made blue: its part of the image, the left tenth (cv2's channels are BGR)
    before, after = (d[32:96, 4:12].reshape(-1, 3).mean(0) for d in decoded[:2])
    assert before[2] > 2 * before[0] and after[0] > 1.5 * after[2], (before, after)
