"""The layout docs/architecture.md describes, pinned: imports run one way (no circle, counting
imports inside functions too), DELMIA's names live only in its host package, and no module
grows past a few hundred lines."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "kingen"
MAX_LINES = 400
DELMIA_ONLY = ("DNBVMAP", "get_kin_config", "kin_check_definition")


def module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules():
    return {module_name(path): path for path in PACKAGE.rglob("*.py")}


def imported(name, path, known):
    """The kingen modules ``name`` (at ``path``) imports anywhere in its body, with the
    packages they live in (importing a.b.c runs a/__init__ and a/b/__init__ first)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        targets = []
        if isinstance(node, ast.ImportFrom):
            base = package
            for _ in range(node.level - 1):
                base = base.rpartition(".")[0]
            base = f"{base}.{node.module}" if node.level and node.module else (base if node.level else node.module)
            targets = [base] + [f"{base}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        for target in targets:
            while target:
                if target in known and target != name:
                    found.add(target)
                target = target.rpartition(".")[0]
    return found


def test_no_import_circle():
    known = modules()
    graph = {name: imported(name, path, known) for name, path in known.items()}
    # A package's __init__ may import its own submodules (they run after it): that edge is
    # the package gathering its parts, not a circle; any other way back is.
    for name in graph:
        graph[name] = {target for target in graph[name] if not target.startswith(name + ".")}
    state, path = {}, []

    def visit(node):
        state[node] = "open"
        path.append(node)
        for target in sorted(graph[node]):
            assert state.get(target) != "open", " -> ".join(path[path.index(target):] + [target])
            if target not in state:
                visit(target)
        path.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node)


def test_delmia_names_live_only_in_its_host_package():
    delmia = PACKAGE / "hosts" / "delmia"
    outside = [f"{path.relative_to(PACKAGE.parent)}: {word}" for path in PACKAGE.rglob("*")
               if path.is_file() and path.suffix in (".py", ".j2", ".c", ".h") and delmia not in path.parents
               for word in DELMIA_ONLY if word in path.read_text()]
    assert outside == []


def test_no_module_grows_past_a_few_hundred_lines():
    long = {str(path.relative_to(PACKAGE.parent)): count for path in PACKAGE.rglob("*.py")
            if (count := len(path.read_text().splitlines())) > MAX_LINES}
    assert long == {}
