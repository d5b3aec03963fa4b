"""Flow's import paths (``flowrun.core``, ``flowrun.utils``, ``flowrun.envs.loop``,
``flowrun.controllers.base_controller``, ...) are thin re-exports at the edge: each says so in
its first docstring line, holds no functions or classes, and no other flowrun module imports
one. (The layers between packages are checked by ``lint-imports``, see
``[tool.importlinter]``.)"""

from __future__ import annotations

import ast
from pathlib import Path

import grimp

ROOT = Path(__file__).resolve().parent.parent
MARK = "Flow compatibility: re-exports."
#: Flow's packages: every module in them is a re-export.
FLOW_PACKAGES = ("flowrun.core", "flowrun.utils", "flowrun.scenarios", "flowrun.visualize",
                 "flowrun.renderer")


def _tree(module: str) -> ast.Module:
    path = ROOT.joinpath(*module.split("."))
    path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
    return ast.parse(path.read_text())


def _faces(graph: grimp.ImportGraph) -> set[str]:
    return {
        m for m in graph.modules if (ast.get_docstring(_tree(m)) or "").startswith(MARK)
    }


def test_every_module_of_flows_packages_is_a_marked_re_export() -> None:
    graph = grimp.build_graph("flowrun")
    faces = _faces(graph)
    in_flow_packages = {
        m for m in graph.modules if m.startswith(tuple(p + "." for p in FLOW_PACKAGES))
    } | set(FLOW_PACKAGES)
    assert in_flow_packages - faces == set()
    assert {"flowrun.envs.loop", "flowrun.envs.multiagent"} <= faces
    assert "flowrun.controllers.base_controller" in faces


def test_re_exports_define_no_functions_or_classes() -> None:
    graph = grimp.build_graph("flowrun")
    for module in sorted(_faces(graph)):
        defined = [
            node.name
            for node in _tree(module).body
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)
            and node.name != "__getattr__"  # lazy re-export of an optional extra
        ]
        assert defined == [], f"{module} defines {defined}: move them into the core"


def test_no_core_module_imports_a_flow_path() -> None:
    graph = grimp.build_graph("flowrun")
    faces = _faces(graph)
    importers = {
        (importer, face)
        for face in faces
        for importer in graph.find_modules_that_directly_import(face)
        if importer not in faces
    }
    assert importers == set()
