"""The package's layout is its architecture: no import circles, no private names
imported across modules, no flat modules beside the layers."""
import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "doe_calib"
#: The only modules allowed directly under doe_calib/ (everything else lives in a layer).
TOP_LEVEL = {"__init__", "__main__", "errors", "result_files"}


def _module(path: Path) -> str:
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict:
    return {_module(p): p for p in PKG.rglob("*.py")}


def _imports(path: Path, modules) -> list:
    """(imported module, names, line) of every import in ``path``, at any depth."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(a.name, [], node.lineno) for a in node.names if a.name.startswith("doe_calib")]
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("doe_calib"):
            assert node.level == 0, f"{path}:{node.lineno}: relative import"
            for a in node.names:  # `from pkg import module` imports the module
                sub = f"{node.module}.{a.name}"
                out.append((sub, [], node.lineno) if sub in modules
                           else (node.module, [a.name], node.lineno))
    return out


def _graph():
    modules = _modules()
    graph = {}
    for name, path in modules.items():
        deps = set()
        for target, _, _ in _imports(path, modules):
            while target not in modules and "." in target:
                target = target.rsplit(".", 1)[0]
            if target != name and target != "doe_calib":
                deps.add(target)
        graph[name] = deps
    return graph


def test_no_import_circle():
    graph = _graph()
    state, stack, cycles = {}, [], []

    def visit(n):
        state[n] = "open"
        stack.append(n)
        for d in sorted(graph.get(n, ())):
            if state.get(d) == "open":
                cycles.append(stack[stack.index(d):] + [d])
            elif d not in state:
                visit(d)
        stack.pop()
        state[n] = "done"

    for n in sorted(graph):
        if n not in state:
            visit(n)
    assert not cycles, "import circles:\n" + "\n".join(" → ".join(c) for c in cycles)


def test_the_walk_sees_imports():
    """The graph is not empty by accident: known edges are there."""
    graph = _graph()
    assert "doe_calib.estimation.preparation" in graph["doe_calib.estimation.point_estimator"]
    assert "doe_calib.model.marker_model" in graph["doe_calib.estimation.identify"]


def test_no_private_name_imported_across_modules():
    modules = _modules()
    bad = [f"{path.relative_to(PKG.parent)}:{line}: {target}.{n}"
           for path in modules.values() for target, names, line in _imports(path, modules)
           for n in names if n.startswith("_")]
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


def test_no_flat_modules_beside_the_layers():
    flat = {p.stem for p in PKG.glob("*.py")} - TOP_LEVEL
    assert not flat, f"modules outside a layer: {sorted(flat)}"


@pytest.mark.parametrize("layer", ["model", "io", "estimation", "design", "diagnosis",
                                   "compensation", "collision", "export", "report", "iso9283",
                                   "cli", "examples", "runtime"])
def test_each_layer_is_a_documented_package(layer):
    init = PKG / layer / "__init__.py"
    assert init.exists() and ast.get_docstring(ast.parse(init.read_text(encoding="utf-8")))
