"""The package keeps its shape: rooms of a few hundred lines (functions are held to McCabe 12
and 60 statements by ruff, the import layers by import-linter; both run in CI)."""

from __future__ import annotations

from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "sindyship"
MAX_LINES = 600


def test_no_module_is_longer_than_a_few_hundred_lines():
    long = {str(p.relative_to(PACKAGE)): n for p in PACKAGE.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert long == {}, f"modules over {MAX_LINES} lines: {long}"


def test_the_generated_simulator_carries_the_kernel_the_library_runs():
    from sindyship.export import generate_python
    from sindyship.model import paper_model
    from sindyship.ships import load_ship
    from sindyship.simulation import kernels

    source = generate_python(paper_model(load_ship("kcs")))
    kernel = (PACKAGE / "simulation" / "kernels.py").read_text(encoding="utf-8")
    body = kernel[kernel.index(kernels.KERNEL_MARK):]
    assert body in source
    assert "def integrate(" in body and "class ZigZagCommand" in body
