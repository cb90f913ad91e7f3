"""Every notebook in notebooks/ runs top to bottom on small data (SINDYSHIP_FAST=1).

The notebooks run one after another in one Jupyter kernel: starting a kernel and importing
sindyship in it cost two seconds per notebook, more than most notebooks take on small data.
Before each, the kernel is brought back to how it started, as far as a kernel can be without
a restart: its namespace cleared (``%reset -f``: a notebook that forgets an import fails), the
environment variables, ``sys.path`` and warning filters it started with restored, any module
imported since from outside the installed packages (a generated simulator) forgotten, figures
closed, matplotlib's settings restored, and its working folder a new temporary folder.  What
stays is what imports leave in the installed packages' modules (a submodule already imported
is an attribute of its package).  A notebook that fails or times out (its cell interrupted)
restarts the kernel for the next.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.py"))

#: Figures a notebook displays (made without pyplot, they show only where displayed): the
#: paths of three equations for each of two optimizers, and the forces of two models.
DISPLAYED_FIGURES = {"02_sparsity_paths": 6, "07_coefficients_with_a_prior": 2}

#: Run once in a new kernel: what :data:`FRESH_START` brings it back to.
SNAPSHOT = """\
import os, sys, types, warnings
import sindyship
start = types.ModuleType("_notebook_test_start")
start.environ, start.path = dict(os.environ), list(sys.path)
start.filters, start.modules = list(warnings.filters), set(sys.modules)
start.installed = (sys.prefix, sys.base_prefix, os.path.dirname(sindyship.__file__))
sys.modules[start.__name__] = start
"""

#: Run in the shared kernel before each notebook, in a folder of its own.
FRESH_START = """\
%reset -f
def _fresh_start(folder):
    import os, sys, warnings
    start = sys.modules["_notebook_test_start"]
    os.environ.clear()
    os.environ.update(start.environ)
    sys.path[:] = start.path
    warnings.resetwarnings()
    warnings.filters[:] = start.filters
    for name in set(sys.modules) - start.modules:
        where = getattr(sys.modules[name], "__file__", None) or start.installed[0]
        if not where.startswith(start.installed):
            del sys.modules[name]
    if "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close("all")
        sys.modules["matplotlib"].rc_file_defaults()
    os.chdir(folder)
    assert os.environ["SINDYSHIP_FAST"] == "1" and os.environ["MPLBACKEND"] == "Agg"
_fresh_start({folder!r})
del _fresh_start
"""


def _run(notebook, manager, timeout: float = 600) -> None:
    """Execute ``notebook`` in the kernel of ``manager`` (a cell past ``timeout`` seconds is
    interrupted), leaving the kernel running."""
    import nbclient

    client = nbclient.NotebookClient(notebook, km=manager, timeout=timeout,
                                     interrupt_on_timeout=True)
    try:
        client.execute()
    finally:
        if client.kc is not None:
            client.kc.stop_channels()


class SharedKernel:
    """A python3 kernel started with SINDYSHIP_FAST=1 and the snapshot taken."""

    def __init__(self):
        from jupyter_client.manager import KernelManager

        self.manager = KernelManager(kernel_name="python3")
        self.manager.start_kernel(env={**os.environ, "SINDYSHIP_FAST": "1",
                                       "MPLBACKEND": "Agg"})
        self._snapshot()

    def _snapshot(self) -> None:
        import nbformat

        _run(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(SNAPSHOT)]),
             self.manager)

    def run(self, notebook, folder: Path, timeout: float = 600) -> None:
        """``notebook`` from a fresh start in ``folder``; the kernel restarts if it fails."""
        import nbformat

        notebook.cells.insert(0, nbformat.v4.new_code_cell(FRESH_START.format(
            folder=str(folder))))
        try:
            _run(notebook, self.manager, timeout)
        except BaseException:
            self.manager.restart_kernel(now=True)
            self._snapshot()
            raise

    def shutdown(self) -> None:
        self.manager.shutdown_kernel(now=True)


@pytest.fixture(scope="module")
def kernel():
    """One kernel for the notebooks of this module, shut down after them."""
    pytest.importorskip("jupytext")
    pytest.importorskip("nbclient")
    shared = SharedKernel()
    try:
        yield shared
    finally:
        shared.shutdown()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, kernel, tmp_path):
    import jupytext

    notebook = jupytext.read(path)
    assert sum(cell.cell_type == "markdown" for cell in notebook.cells) >= 3
    kernel.run(notebook, tmp_path)
    errors = [o for cell in notebook.cells if cell.cell_type == "code"
              for o in cell.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
    # a figure made without pyplot shows only where it is displayed, and never empty
    shown = [o["data"].get("text/plain", "") for cell in notebook.cells
             if cell.cell_type == "code" for o in cell.get("outputs", [])
             if o.get("output_type") == "display_data"]
    figures = [text for text in shown if text.startswith("<Figure")]
    assert len(figures) >= DISPLAYED_FIGURES.get(path.stem, 0), shown
    assert not [text for text in figures if "with 0 Axes" in text]


def test_a_fresh_start_forgets_what_an_earlier_notebook_left(kernel, tmp_path):
    """Names, environment variables, warning filters and generated modules of one notebook
    are gone for the next; a failing notebook leaves a working kernel."""
    import nbclient
    import nbformat

    made, later_folder = tmp_path / "made", tmp_path / "later"
    made.mkdir()
    later_folder.mkdir()
    (made / "generated_here.py").write_text("VALUE = 1\n")
    earlier = ["import numpy as np", "import os; os.environ['LEFT_BEHIND'] = '1'",
               "import warnings; warnings.simplefilter('error')",
               f"import sys; sys.path.insert(0, {str(made)!r}); import generated_here"]
    kernel.run(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in earlier]),
               made)
    later = ["assert {'np', 'name', 'os', 'sys', 'start'}.isdisjoint(dir())",
             "import os; assert 'LEFT_BEHIND' not in os.environ",
             "import warnings; warnings.warn('only a warning')",
             "import sys; assert 'generated_here' not in sys.modules and "
             f"{str(made)!r} not in sys.path"]
    kernel.run(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in later]),
               later_folder)
    with pytest.raises(nbclient.exceptions.CellExecutionError, match="NameError"):
        kernel.run(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("np.zeros(3)")]),
                   later_folder)
    kernel.run(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1 + 1")]),
               later_folder)  # the kernel restarted after the failure
