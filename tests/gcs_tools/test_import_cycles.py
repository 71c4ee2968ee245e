"""gcs_tools' modules import each other without cycles (lazy imports inside functions included)."""

import ast
import importlib.util
from pathlib import Path

import gcs_tools

ROOT = Path(gcs_tools.__file__).resolve().parent


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(ROOT.parent).with_suffix("").parts).removesuffix(".__init__")


def _edges(path: Path, known: set[str]) -> set[str]:
    """The gcs_tools modules this file imports: ``from a.b import c`` counts as ``a.b.c`` when
    that is a module, else as ``a.b``."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name in known)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module in known:
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                out.add(sub if sub in known else node.module)
    return out - {_module_name(path)}


def import_graph() -> dict[str, set[str]]:
    files = sorted(ROOT.rglob("*.py"))
    known = {_module_name(p) for p in files}
    return {_module_name(p): _edges(p, known) for p in files}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(u):
        state[u] = 1
        stack.append(u)
        for v in sorted(graph[u]):
            if state.get(v) == 1:
                return stack[stack.index(v):] + [v]
            if v not in state and (found := visit(v)):
                return found
        stack.pop()
        state[u] = 2
        return None

    for m in sorted(graph):
        if m not in state and (found := visit(m)):
            return found
    return None


def test_the_cycle_finder_finds_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_gcs_tools_has_no_import_cycle():
    graph = import_graph()
    assert "gcs_tools.param_cli" in graph and importlib.util.find_spec("gcs_tools.cli")
    assert find_cycle(graph) is None, f"import cycle: {' -> '.join(find_cycle(graph))}"
