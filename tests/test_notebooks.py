"""Every notebook in notebooks/ runs top to bottom on small data (SINDYSHIP_FAST=1).

The notebooks run one after another in one Jupyter kernel, as a user's session would: before
each, the kernel's namespace is cleared (``%reset -f``, so a notebook that forgets an import
fails), its figures closed, matplotlib's settings restored and its working folder moved to a
new temporary folder.  Starting a kernel and importing sindyship in it cost two seconds per
notebook, more than most notebooks take on small data.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.py"))

#: Run in the shared kernel before each notebook: a clean namespace in a folder of its own.
FRESH_START = """\
%reset -f
import os
import matplotlib
import matplotlib.pyplot
matplotlib.pyplot.close("all")
matplotlib.rcdefaults()
os.chdir({folder!r})
assert os.environ["SINDYSHIP_FAST"] == "1" and os.environ["MPLBACKEND"] == "Agg"
del os, matplotlib
"""


@pytest.fixture(scope="module")
def kernel():
    """One python3 kernel for the notebooks of this module, shut down after them."""
    pytest.importorskip("jupytext")
    pytest.importorskip("nbclient")
    from jupyter_client.manager import KernelManager

    manager = KernelManager(kernel_name="python3")
    manager.start_kernel(env={**os.environ, "SINDYSHIP_FAST": "1", "MPLBACKEND": "Agg"})
    try:
        yield manager
    finally:
        manager.shutdown_kernel(now=True)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, kernel, tmp_path):
    import jupytext
    import nbclient
    import nbformat

    notebook = jupytext.read(path)
    assert sum(cell.cell_type == "markdown" for cell in notebook.cells) >= 3
    notebook.cells.insert(0, nbformat.v4.new_code_cell(FRESH_START.format(folder=str(tmp_path))))
    client = nbclient.NotebookClient(notebook, km=kernel, timeout=600)
    try:
        client.execute()
    finally:
        if client.kc is not None:
            client.kc.stop_channels()
    errors = [o for cell in notebook.cells if cell.cell_type == "code"
              for o in cell.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors


def test_a_notebook_that_uses_a_name_an_earlier_one_made_fails(kernel, tmp_path):
    """The fresh start clears what an earlier notebook defined: sharing the kernel hides no
    missing import."""
    import nbclient
    import nbformat

    first = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import numpy as np")])
    second = nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_code_cell(FRESH_START.format(folder=str(tmp_path))),
        nbformat.v4.new_code_cell("np.zeros(3)")])
    for notebook in (first, second):
        client = nbclient.NotebookClient(notebook, km=kernel, timeout=60)
        try:
            if notebook is first:
                client.execute()
            else:
                with pytest.raises(nbclient.exceptions.CellExecutionError, match="NameError"):
                    client.execute()
        finally:
            if client.kc is not None:
                client.kc.stop_channels()
