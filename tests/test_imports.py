"""The package's import graph has no cycles (issue 20, item 5) and the kernels sit below
everything else (item 2), counting deferred imports
(inside functions) and by-name imports (a module's dotted name written as a string, e.g. the
CLI's SUBCOMMANDS), and no module edits sys.path. Imports under ``if TYPE_CHECKING:`` are not
executed and are not counted. A module importing ``pkg.sub`` counts as depending on ``pkg.sub``
(Python also runs ``pkg/__init__`` first, but that is the parent package, not a dependency)."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "chainmodel"


def _modules() -> dict[str, Path]:
    mods = {}
    for f in PACKAGE.rglob("*.py"):
        parts = list(f.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = f
    return mods


def _type_checking_nodes(tree) -> set[int]:
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                skip.update(id(n) for n in ast.walk(sub))
    return skip


def _imports(name: str, path: Path, mods: dict[str, Path]) -> set[str]:
    """The package modules ``name`` imports, anywhere in its source."""
    tree = ast.parse(path.read_text())
    skip = _type_checking_nodes(tree)
    base = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    deps: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            deps.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parent = base[:len(base) - (node.level - 1)]
                target = ".".join(parent + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in mods]
            if len(subs) < len(node.names):
                deps.add(target)
            deps.update(subs)
        elif (isinstance(node, ast.Constant) and isinstance(node.value, str)
              and "." in node.value and node.value in mods):
            deps.add(node.value)
    deps.discard(name)
    return deps & set(mods)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles_in_chainmodel():
    mods = _modules()
    graph = {name: _imports(name, path, mods) for name, path in mods.items()}
    assert graph["chainmodel.cli"], "the import finder found nothing: it is broken"
    assert _cycles(graph) == []


def test_no_sys_path_edits_in_chainmodel():
    edits = [str(p.relative_to(PACKAGE.parent)) for p in PACKAGE.rglob("*.py")
             if "sys.path.insert" in p.read_text() or "sys.path.append" in p.read_text()]
    assert edits == []


#: what the kernels (chainmodel.kernels) must never import, directly or through another module
KERNEL_FORBIDDEN = ("chainmodel.models", "chainmodel.scene", "chainmodel.cli", "chainmodel.fmu",
                    "chainmodel.analysis", "chainmodel.integrate", "chainmodel.simulation",
                    "chainmodel.cosim")


def test_kernels_import_nothing_above_them():
    """Layers run one way (docs/architecture.md): the kernel package imports only the base
    modules and the kinematics, never the models, steppers, scenes, CLI, FMU or analysis tools -
    counting the modules those import in turn."""
    mods = _modules()
    graph = {name: _imports(name, path, mods) for name, path in mods.items()}
    kernel_modules = [m for m in mods if m == "chainmodel.kernels" or
                      m.startswith("chainmodel.kernels.")]
    assert len(kernel_modules) > 5, "the kernel package was not found"
    for start in kernel_modules:
        bad = _forbidden(graph, start)
        assert bad == [], f"{start} imports {bad}"


def _forbidden(graph: dict[str, set[str]], start: str) -> list[str]:
    """The KERNEL_FORBIDDEN modules that ``start`` reaches in ``graph``."""
    seen, todo = set(), [start]
    while todo:
        for dep in graph.get(todo.pop(), set()) - seen:
            seen.add(dep)
            todo.append(dep)
    return sorted(d for d in seen if d.startswith(KERNEL_FORBIDDEN))


def test_the_layer_check_finds_a_forbidden_import():
    graph = {"chainmodel.kernels.a": {"chainmodel.geometry"},
             "chainmodel.geometry": {"chainmodel.models.base"}}
    assert _forbidden(graph, "chainmodel.kernels.a") == ["chainmodel.models.base"]
    assert _forbidden({"chainmodel.kernels.a": {"chainmodel.units"}}, "chainmodel.kernels.a") == []
