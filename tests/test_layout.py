"""The package's layout shows its architecture (README.md, "Layout"): app/'s top level holds a few
modules, the rest grouped by concern into subpackages; no module imports, directly or through
others, a module that imports it; and no source file grows past what one reads at a sitting.

Imports are read from the source (ast), not run. Both a module's top-level imports and those
inside its functions count: a function-level import defers the cost of loading a module, not the
dependency, and a circle through one still ties the two modules together (it also breaks as soon
as someone moves the import to the top). `from pathtrace.x import y` depends on the module
pathtrace.x.y where that is a module, else on pathtrace.x. A package's __init__ is the module of
the package's name; importing pathtrace.x.y is not counted as importing pathtrace.x, which Python
runs first but which is the package's own business (its __init__ gathers its modules)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
APP = ROOT / "app"

MAX_TOP_LEVEL_MODULES = 8
MAX_LINES = 600


def module_name(path: Path) -> str:
    parts = ["pathtrace", *path.relative_to(APP).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(APP.rglob("*.py"))}


def resolve(name: str) -> str | None:
    """The module `name` names, or the nearest package or module above it."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def imports(module: str) -> set:
    """The modules of pathtrace that `module` imports, at its top level or in its functions."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found |= {resolve(a.name) for a in node.names if a.name.split(".")[0] == "pathtrace"}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:               # relative: from the package, up level - 1
                up = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            if base.split(".")[0] == "pathtrace":
                found |= {resolve(f"{base}.{a.name}") if f"{base}.{a.name}" in MODULES else resolve(base)
                          for a in node.names}
    return found - {module, None}


def circles(graph: dict) -> list:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

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
            while not component or component[-1] != v:
                component.append(stack.pop())
                on_stack.discard(component[-1])
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_the_import_graph_is_read():
    """The reading itself, on modules whose imports are known: a test of the tests below."""
    assert {"pathtrace.errors", "pathtrace.scene.description"} <= imports("pathtrace.api")
    assert "pathtrace.cli.main" in imports("pathtrace.cli.console")          # inside run()
    assert "pathtrace.rendering.renderer" in imports("pathtrace.cli.listing")  # inside warm_up()
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_circle():
    graph = {m: imports(m) for m in MODULES}
    assert circles(graph) == []


def test_the_top_level_holds_few_modules():
    top = sorted(p.name for p in APP.glob("*.py"))
    assert len(top) <= MAX_TOP_LEVEL_MODULES, f"app/ has {len(top)} modules: {top}; put them in a subpackage"


def test_no_source_file_is_too_long():
    files = [*APP.rglob("*.py"), *(ROOT / "kernels").rglob("*.cl"), *(ROOT / "kernels").rglob("*.h")]
    lengths = {str(f.relative_to(ROOT)): len(f.read_text().splitlines()) for f in files}
    assert {f: n for f, n in lengths.items() if n > MAX_LINES} == {}


def test_the_performance_summary_stays_a_summary():
    """docs/performance.md holds today's design decisions and their measured reasons, at most
    400 lines (issue #56); their history is the dated log under docs/notes/."""
    lines = len((ROOT / "docs" / "performance.md").read_text().splitlines())
    assert lines <= 400, f"docs/performance.md has {lines} lines: move history to docs/notes/"
