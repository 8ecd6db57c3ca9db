"""The layout docs/architecture.md describes, pinned: imports run one way, down the layers
(no circle, no import of a higher layer, counting imports inside functions too), DELMIA's
names live only in its host package, the package's top holds a handful of modules, and no
module grows past a few hundred lines."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "kingen"
MAX_LINES = 400
DELMIA_ONLY = ("DNBVMAP", "get_kin_config", "kin_check_definition", "kinstat", "KinStat", "delmia_type",
               "delmia_axis", "Actuator Space", "kin_{", "lib{", "dialog_label", "dialog_value", "DialogField")
"""DELMIA's symbols and names, and how it names a robot's routine, library, calibration fields and
joint types: kingen/hosts/delmia/ alone says them; the rest asks the host (kingen.hosts.base.Host)."""
HOST_NEUTRAL = ("foundation", "runtime", "robot", "kinematics")
"""The layers that name no host at all: the robot, its model and its kinematics."""


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


LAYERS = (
    ("foundation", ("kingen.errors", "kingen.conventions", "kingen.units", "kingen.defaults", "kingen.vendor")),
    ("runtime", ("kingen.runtime",)),
    ("robot", ("kingen.robot", "kingen.limbs")),
    ("kinematics", ("kingen.kinematics",)),
    ("verify", ("kingen.verify",)),
    ("hosts", ("kingen.hosts",)),
    ("design", ("kingen.design",)),
    ("interface", ("kingen.cli", "kingen.pytest_plugin", "kingen")),
)
"""kingen's layers, lowest first (docs/architecture.md): a module may import its own layer's
and lower ones' modules, never a higher one's. ``kingen`` itself is the public face, on top."""


def layer(name):
    """The index in LAYERS of module ``name``'s layer (its longest matching prefix)."""
    matches = [(len(prefix), index) for index, (_, prefixes) in enumerate(LAYERS) for prefix in prefixes
               if name == prefix or name.startswith(prefix + ".")]
    assert matches, f"{name} is in no layer: add it to LAYERS and docs/architecture.md"
    return max(matches)[1]


def upward_imports(graph):
    """'a (layer) -> b (layer)' for every import in ``graph`` (module -> modules it imports)
    of a module in a higher layer. Importing a module runs its packages' __init__ first, but
    the root package's is the lazy public face, which imports nothing when it runs: it counts
    only where a module names it."""
    found = []
    for name, targets in sorted(graph.items()):
        for target in sorted(targets):
            if layer(target) > layer(name):
                found.append(f"{name} ({LAYERS[layer(name)][0]}) -> {target} ({LAYERS[layer(target)][0]})")
    return found


def import_graph():
    """Module -> the kingen modules it imports anywhere in its body (imports inside functions
    counted), the root package only where it is named."""
    known = modules()
    graph = {}
    for name, path in known.items():
        named = _names_root(path)
        graph[name] = {target for target in imported(name, path, known)
                       if target != "kingen" or named}
    return graph


def _names_root(path):
    """Whether the module at ``path`` imports the root package by name (``import kingen``,
    ``from kingen import x``, or a relative import that climbs to it)."""
    depth = len(path.relative_to(PACKAGE).parts)  # the level of a relative import that climbs to it
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import) and any(alias.name == "kingen" for alias in node.names):
            return True
        if isinstance(node, ast.ImportFrom):
            if node.level == 0 and node.module == "kingen":
                return True
            if node.level and not node.module and node.level == depth:
                return True
    return False


def test_imports_run_down_the_layers():
    assert upward_imports(import_graph()) == []


def test_a_planted_upward_import_fails_the_layer_test():
    graph = import_graph()
    graph["kingen.robot.model"] = graph["kingen.robot.model"] | {"kingen.hosts"}
    graph["kingen.errors"] = graph["kingen.errors"] | {"kingen"}
    assert upward_imports(graph) == ["kingen.errors (foundation) -> kingen (interface)",
                                     "kingen.robot.model (robot) -> kingen.hosts (hosts)"]


def test_the_top_of_the_package_holds_a_handful_of_modules():
    top = sorted(path.name for path in PACKAGE.glob("*.py"))
    assert len(top) <= 6, top


def test_delmia_names_live_only_in_its_host_package():
    delmia = PACKAGE / "hosts" / "delmia"
    outside = [f"{path.relative_to(PACKAGE.parent)}: {word}" for path in PACKAGE.rglob("*")
               if path.is_file() and path.suffix in (".py", ".j2", ".c", ".h") and delmia not in path.parents
               for word in DELMIA_ONLY if word in path.read_text()]
    assert outside == []


def test_the_host_neutral_layers_name_no_host():
    """Only the setting of which host commands use by default (``DEFAULT_HOST``, read before
    anything heavy loads) may spell a host's name below the hosts: it is a choice, not
    knowledge of that host."""
    known = modules()
    named = [f"{path.relative_to(PACKAGE.parent)}: {word}" for name, path in sorted(known.items())
             if LAYERS[layer(name)][0] in HOST_NEUTRAL
             for word in ("delmia", "igrip")
             if word in "".join(line for line in path.read_text().lower().splitlines(True)
                                if not line.startswith("default_host = "))]
    assert named == []


def test_no_module_grows_past_a_few_hundred_lines():
    long = {str(path.relative_to(PACKAGE.parent)): count for path in PACKAGE.rglob("*.py")
            if (count := len(path.read_text().splitlines())) > MAX_LINES}
    assert long == {}
