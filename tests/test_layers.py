"""Imports run downhill: no module imports a layer above its own.

The layers, lowest first: errors, runtime, io, model, estimation, collision, design,
diagnosis, compensation, export, report, iso9283, examples, cli, then the top-level API
(``doe_calib/__init__.py``, ``__main__.py``, ``result_files.py``), which may import
every layer. Every import is walked, inside functions too: ``import x``, ``from x
import y`` (relative ones resolved) and ``import_module("x")`` with a literal name.
"""
import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "doe_calib"
LAYERS = ("errors", "runtime", "io", "model", "estimation", "collision", "design",
          "diagnosis", "compensation", "export", "report", "iso9283", "examples", "cli")
TOP = len(LAYERS)


def _module(path: Path) -> str:
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def layer(module: str) -> int:
    """Rank of the layer ``module`` (dotted, ``doe_calib.…``) belongs to; TOP for the API."""
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else TOP


def imports(source: str, module: str, is_package: bool = False) -> list:
    """(imported module, line) of every import of doe_calib in ``source`` (the text of
    ``module``), at any depth.

    ``from doe_calib import X`` and ``from . import X`` name the module ``….X``: a layer
    when X is one (``examples``), else, from ``doe_calib``, the top-level API.
    """
    package = module if is_package else module.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            parts = package.split(".")
            base = ".".join(parts[:len(parts) - node.level + 1]) if node.level else ""
            target = ".".join(filter(None, [base, node.module]))
            if node.module is None or target == "doe_calib":
                out += [(f"{target}.{a.name}", node.lineno) for a in node.names]
            else:
                out.append((target, node.lineno))
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(
                node.func, "id", None)) == "import_module" and node.args and \
                isinstance(node.args[0], ast.Constant):
            out.append((node.args[0].value, node.lineno))
    return [(t, line) for t, line in out if t == "doe_calib" or t.startswith("doe_calib.")]


def _walk() -> list:
    """(module, line, imported module) for every import of doe_calib in the package."""
    return [(_module(p), line, target) for p in sorted(PKG.rglob("*.py"))
            for target, line in imports(p.read_text(encoding="utf-8"), _module(p),
                                        p.name == "__init__.py")]


def test_no_import_runs_uphill():
    uphill = [f"{m}:{line} imports {t} ({LAYERS[layer(m)] if layer(m) < TOP else 'top'} → "
              f"{LAYERS[layer(t)] if layer(t) < TOP else 'top'})"
              for m, line, t in _walk() if layer(t) > layer(m)]
    assert not uphill, "imports of a higher layer:\n" + "\n".join(uphill)


def test_the_walk_sees_every_kind_of_import():
    """Not vacuous: the walk finds hundreds of imports, known ones, and each kind, inside
    functions too."""
    walked = _walk()
    assert len(walked) > 500, len(walked)
    found = {(m, t) for m, _, t in walked}
    assert ("doe_calib.estimation.identify", "doe_calib.model.marker_model") in found
    assert ("doe_calib", "doe_calib.examples") in found  # import_module with a literal name
    source = "import doe_calib.io\ndef f():\n    from doe_calib import examples, Robot\n"
    assert imports(source, "doe_calib.model.robot") == [
        ("doe_calib.io", 1), ("doe_calib.examples", 3), ("doe_calib.Robot", 3)]


def test_relative_imports_are_resolved():
    source = ("from ..report import design\nfrom . import comparison\n"
              "def f():\n    from .. import examples\n")
    assert imports(source, "doe_calib.design.result") == [
        ("doe_calib.report", 1), ("doe_calib.design.comparison", 2),
        ("doe_calib.examples", 4)]
    assert imports("from .json_file import read_json\n", "doe_calib.io", is_package=True) == [
        ("doe_calib.io.json_file", 1)]


def test_layer_ranks():
    assert layer("doe_calib.errors") < layer("doe_calib.io.csv_files") < \
        layer("doe_calib.model.effects.user") < layer("doe_calib.report.notebook") < \
        layer("doe_calib.cli.identify") < layer("doe_calib") == layer("doe_calib.result_files")
