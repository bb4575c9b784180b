"""The example notebook (examples/quickstart.ipynb) runs top to bottom in a fresh kernel: synthetic
capture -> registration -> volumes against the truth (its own assertion: trunk_limbs within 5 %) -> a
figure -> exports (PLY, OBJ with one group per segment, JSON, trimesh / Open3D objects)."""

from __future__ import annotations

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat", reason="nbformat not installed (pip install -r requirements-dev.txt)")
nbclient = pytest.importorskip("nbclient", reason="nbclient not installed (pip install -r requirements-dev.txt)")

NOTEBOOK = Path(__file__).resolve().parents[2] / "examples" / "quickstart.ipynb"


def test_quickstart_notebook_runs(tmp_path: Path) -> None:
    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert not any(c.get("outputs") for c in nb.cells if c.cell_type == "code"), "commit the notebook without outputs"
    client = nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    html = [o["data"]["text/html"] for o in outputs if o.output_type == "execute_result" and "text/html" in o["data"]]
    assert any("data:image/png;base64," in h and "trunk_limbs" in h for h in html), "the fit's table and thumbnail"
    assert any("image/png" in o.get("data", {}) for o in outputs if o.output_type == "display_data"), "the figure"
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "OBJ groups:" in text and "g torso" in text
