"""The house rules of DESIGN.md on imports, checked over every module of the repository.

* No import circles: the graph of module-level imports among mechgen's modules (what runs when a
  module is first imported; imports inside functions and ``if TYPE_CHECKING:`` blocks are not
  executed then and are left out) has no cycle. Importing ``a.b.c`` also runs the packages
  ``a`` and ``a.b``, so those are edges too, except for packages that contain the importer.
* No private name (``_x``) imported across modules: no ``from mechgen... import _x`` and no
  ``module._x`` on a mechgen module bound by an import, in mechgen/, tests/ and benchmarks/.
  A helper that two modules need is public where it lives.

Both tests parse the sources (nothing is imported), and both were seen to fail on the circles and
private imports that existed before the rule (runtime.bvp <-> runtime.collocation;
codegen.emit_casadi importing emit_numpy._extent, ...).
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "mechgen"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _sources(*folders: str) -> dict[str, Path]:
    """module name -> file, for the .py files under the given folders of the repository."""
    out = {}
    for folder in folders:
        for path in sorted((ROOT / folder).rglob("*.py")):
            if "__pycache__" in path.parts or "generated" in path.relative_to(ROOT).parts:
                continue
            out[_module_name(path)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _top_level_imports(tree: ast.Module):
    """The Import/ImportFrom nodes executed when the module is imported (not in functions or classes'
    methods, not under ``if TYPE_CHECKING``)."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        elif isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
        else:
            stack.extend(child for child in ast.iter_child_nodes(node) if isinstance(child, ast.stmt))


def _absolute(module: str, node: ast.ImportFrom, is_package: bool) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".")
    base = base if is_package else base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imported(module: str, path: Path, modules: dict[str, Path]):
    """(node, target module, names) of every import of a mechgen module in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node, alias.name, ()
        elif isinstance(node, ast.ImportFrom):
            yield node, _absolute(module, node, path.name == "__init__.py"), tuple(a.name for a in node.names)


def _graph() -> dict[str, set[str]]:
    modules = _sources("mechgen")
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        parts = name.split(".")
        own = {".".join(parts[:i]) for i in range(1, len(parts))}  # the packages that contain the importer
        for node in _top_level_imports(tree):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                base = _absolute(name, node, path.name == "__init__.py")
                targets = [base] + [f"{base}.{alias.name}" for alias in node.names]
            for target in targets:
                if target not in modules:
                    continue
                parts = target.split(".")
                for i in range(1, len(parts) + 1):
                    step = ".".join(parts[:i])
                    if step in modules and step != name and (step == target or step not in own):
                        graph[name].add(step)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
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


def test_graph_sees_the_imports():
    graph = _graph()
    assert "mechgen.runtime.core.kernels" in graph["mechgen.runtime.core.system"]
    assert "mechgen.runtime.steady.bvp" in graph["mechgen.runtime.steady.collocation"]
    # a cycle made on purpose is found
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycles():
    cycles = _cycles(_graph())
    assert not cycles, "module-level import cycles among mechgen's modules:\n" + "\n".join(
        " <-> ".join(c) for c in cycles)


def _private_uses(module: str, path: Path, modules: dict[str, Path]) -> list[str]:
    """'file:line: what' for each private name imported from, or read off, another mechgen module."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    out = []
    bound: dict[str, str] = {}  # local name -> mechgen module it is bound to
    for node, target, names in _imported(module, path, modules):
        if not target.startswith("mechgen") or target == module:
            continue
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.asname:
                    bound[alias.asname] = alias.name
                for part in alias.name.split(".")[1:]:
                    if part.startswith("_") and not part.startswith("__"):
                        out.append(f"{path.relative_to(ROOT)}:{node.lineno}: import {alias.name}")
            continue
        if any(part.startswith("_") and not part.startswith("__") for part in target.split(".")):
            out.append(f"{path.relative_to(ROOT)}:{node.lineno}: from {target}")
        for alias in node.names:
            if alias.name.startswith("_") and not alias.name.startswith("__"):
                out.append(f"{path.relative_to(ROOT)}:{node.lineno}: from {target} import {alias.name}")
            elif f"{target}.{alias.name}" in modules:
                bound[alias.asname or alias.name] = f"{target}.{alias.name}"
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in bound
                and node.attr.startswith("_") and not node.attr.startswith("__")):
            out.append(f"{path.relative_to(ROOT)}:{node.lineno}: {bound[node.value.id]}.{node.attr}")
    return out


def test_private_checker_sees_a_private_import(tmp_path):
    fake = tmp_path / "x.py"
    fake.write_text("from mechgen.codegen.emit_numpy import _extent\n"
                    "from mechgen.runtime.core import system\n"
                    "system._hidden\n")
    global ROOT
    root, ROOT = ROOT, tmp_path
    try:
        found = _private_uses("x", fake, {"mechgen.runtime.core.system": fake})
    finally:
        ROOT = root
    assert found == ["x.py:1: from mechgen.codegen.emit_numpy import _extent",
                     "x.py:3: mechgen.runtime.core.system._hidden"]


def test_no_private_names_across_modules():
    modules = _sources("mechgen", "tests", "benchmarks")
    found = [use for name, path in modules.items() for use in _private_uses(name, path, modules)]
    assert not found, "private names used across modules (make them public where they live):\n" + "\n".join(found)


def _every_import(tree: ast.Module):
    """Every Import/ImportFrom node of the module, those inside functions included (not under TYPE_CHECKING)."""
    skipped = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If) and _is_type_checking(node)
               for n in ast.walk(node)}
    return (node for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in skipped)


#: circles that run only through imports inside functions and are still to be undone (issue 30, house): the
#: package's lazy public entry points (mechgen.compile, mechgen.run ... import the pipeline and the scene layer
#: on first use). A new circle fails the test below; an undone one must leave here.
KNOWN_FUNCTION_LEVEL_CIRCLES = [
    ["mechgen", "mechgen.analyses.result", "mechgen.pipeline", "mechgen.scene.info", "mechgen.scene.load",
     "mechgen.scene.plan", "mechgen.scene.run"],
]


def test_no_new_function_level_import_circles(monkeypatch):
    """Imports inside functions counted too: the circles are exactly the known ones, none added."""
    monkeypatch.setattr(sys.modules[__name__], "_top_level_imports", _every_import)
    assert sorted(_cycles(_graph())) == sorted(KNOWN_FUNCTION_LEVEL_CIRCLES)
