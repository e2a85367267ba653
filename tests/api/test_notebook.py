"""examples/notebook.ipynb runs top to bottom on a real Jupyter kernel
(nbclient, ipykernel; the test extra installs them): the diagnosis names the
friction the notebook's nominal set leaves out, and the corrected set
estimates better."""
from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[2] / "examples" / "notebook.ipynb"

pytestmark = pytest.mark.slow  # a diagnosis of 10 s and four estimates: about a minute on 2 cores


def test_the_notebook_runs_on_a_kernel(tmp_path):
    import nbformat
    from nbclient import NotebookClient
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    assert not any(c.get("outputs") for c in notebook.cells if c.cell_type == "code"), "commit it without outputs"
    NotebookClient(notebook, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    code = [c for c in notebook.cells if c.cell_type == "code"]
    assert not [o for c in code for o in c.outputs if o.output_type == "error"]

    def shown(index: int, kind: str = "text/plain") -> str:
        return "".join(o["data"].get(kind, "") for o in code[index].outputs if o.output_type == "execute_result")

    assert "Recording(in memory: 10001 samples" in shown(2)
    assert "viscous_friction" in shown(5) and "verdict: missing_physics" in shown(5, "text/html")
    assert "Finding(viscous_friction, added in the motor: Bm = " in shown(6)
    assert any(o.output_type == "display_data" and "image/png" in o["data"] for o in code[7].outputs)
    before_after = eval(shown(8))  # {estimate: (RMS error with the nominal set, with the corrected one)}
    assert all(after < before for before, after in before_after.values())
    assert (tmp_path / "report.html").stat().st_size > 10000
