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


def _imports_of(path: Path, module: str, is_package: bool, known: set[str]) -> set[str]:
    """The sindyship modules ``module`` imports anywhere in its file (inside functions and
    methods too), except under ``if TYPE_CHECKING:``, which never runs."""
    import ast

    tree = ast.parse(path.read_text(encoding="utf-8"))
    skipped = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skipped |= {id(n) for child in node.body for n in ast.walk(child)}
    package = module if is_package else module.rpartition(".")[0]

    def resolve(name: str) -> str | None:
        while name and name not in known:
            name = name.rpartition(".")[0]
        return name or None

    found = set()
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package
            for _ in range(max(node.level - 1, 0)):
                base = base.rpartition(".")[0]
            stem = (base + "." + node.module if node.module else base) if node.level \
                else (node.module or "")
            names = [f"{stem}.{alias.name}" if f"{stem}.{alias.name}" in known else stem
                     for alias in node.names]
        else:
            continue
        found |= {target for name in names if name.startswith("sindyship")
                  and (target := resolve(name)) not in (None, module)}
    return found


def _import_graph() -> dict[str, set[str]]:
    files = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        files[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    known = set(files)
    return {module: _imports_of(path, module, is_package, known)
            for module, (path, is_package) in files.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle_counting_imports_inside_functions():
    graph = _import_graph()
    assert len(graph) > 100 and "sindyship.model" in graph["sindyship.refine"]
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle_through_a_function():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(graph) == [["a", "b", "c"]]
