"""The layout docs/developer/architecture.md describes, pinned: imports run one way, down the layers
(no circle, no import of a higher layer, counting imports inside functions too), DELMIA's
names live only in its host package, the package's top holds a handful of modules, no
module grows past a few hundred lines, and no code (Python, C, C templates) stands twice."""

import ast
import io
import keyword
import re
import sys
import tokenize
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
    ("robot", ("kingen.robot",)),
    ("kinematics", ("kingen.kinematics",)),
    ("verify", ("kingen.verify",)),
    ("hosts", ("kingen.hosts",)),
    ("view", ("kingen.view",)),
    ("design", ("kingen.design", "kingen.calibrate")),
    ("paths", ("kingen.paths",)),
    ("interface", ("kingen.cli", "kingen.pytest_plugin", "kingen")),
)
"""kingen's layers, lowest first (docs/developer/architecture.md): a module may import its own layer's
and lower ones' modules, never a higher one's. ``kingen`` itself is the public face, on top."""


def layer(name):
    """The index in LAYERS of module ``name``'s layer (its longest matching prefix)."""
    matches = [(len(prefix), index) for index, (_, prefixes) in enumerate(LAYERS) for prefix in prefixes
               if name == prefix or name.startswith(prefix + ".")]
    assert matches, f"{name} is in no layer: add it to LAYERS and docs/developer/architecture.md"
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


SAME_SHAPE_RUN = 6
"""Duplicated code: a run of this many lines of the same shape standing in two places."""
C_SUFFIXES = (".c", ".h", ".c.j2", ".h.j2")
PLACEHOLDERS = {"N", "0", "S"}
"""What a line's names (and a template's ``{{ }}`` substitutions), numbers and strings become
in its shape."""
DECLARATION = re.compile(r"N(?: : [N.,\[\] ]+?)?(?: = (?:- )?(?:0|S|N|True|False|None))?")
"""The shape of a line that only names a value or a type (a constant, a dataclass field)."""
C_WORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register return short signed sizeof static struct switch typedef union unsigned void volatile while "
    "as call elif endcall endfor endif endmacro endwith import in include is macro not and or set with".split())
"""C's keywords and jinja2's statement words: kept in a C line's shape, as Python's keywords are."""
C_COMMENT = re.compile(r'"(?:\\.|[^"\\\n])*"|/\*.*?\*/|//[^\n]*|\{#.*?#\}', re.DOTALL)
C_TOKEN = re.compile(r'"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'|\{\{.*?\}\}|[A-Za-z_]\w*|\.?\d[\w.]*|\S')


def _c_placeholder(token):
    """A C token's part in its line's shape."""
    if token[0] in "\"'":
        return "S"
    if token.startswith("{{") or (token[0].isalpha() or token[0] == "_") and token not in C_WORDS:
        return "N"
    if token[0].isdigit() or token[0] == "." and len(token) > 1:
        return "0"
    return token


def c_shapes(text):
    """[(line number, shape)] of a C file or C template: names, numbers, strings and
    ``{{ }}`` substitutions as placeholders, C keywords and jinja2's words kept; comments
    (C's and jinja2's) and #include lines left out."""
    text = C_COMMENT.sub(lambda match: match.group() if match.group()[0] == '"' else "\n" * match.group().count("\n"),
                         text)
    return [(number, " ".join(_c_placeholder(token) for token in C_TOKEN.findall(line)))
            for number, line in enumerate(text.splitlines(), 1) if not line.lstrip().startswith("#include")]


def python_shapes(text):
    """[(line number, shape)] of a Python module: names, numbers and strings as placeholders
    (an f-string one string), keywords kept; comments, docstrings (statements that are only a
    string) and imports left out."""
    rows, statement, depth = {}, [], 0
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type in (tokenize.NL, tokenize.COMMENT, tokenize.INDENT, tokenize.DEDENT, tokenize.ENCODING):
            continue
        if token.type in (tokenize.NEWLINE, tokenize.ENDMARKER):
            words = [word for _, word in statement]
            if words and words[0] not in ("import", "from") and set(words) != {"S"}:
                for row, word in statement:
                    rows.setdefault(row, []).append(word)
            statement = []
            continue
        if token.type == getattr(tokenize, "FSTRING_START", None):  # Python 3.12: an f-string in parts
            depth += 1
            if depth == 1:
                statement.append((token.start[0], "S"))
        elif token.type == getattr(tokenize, "FSTRING_END", None):
            depth -= 1
        elif not depth:
            word = {tokenize.NUMBER: "0", tokenize.STRING: "S"}.get(token.type, token.string)
            if token.type == tokenize.NAME and not keyword.iskeyword(word):
                word = "N"
            statement.append((token.start[0], word))
    return [(row, " ".join(words)) for row, words in sorted(rows.items())]


def same_shape_runs(sources):
    """'a:10-17 ~ b:40-47' for each pair of places (the first of each pair of files) where
    ``sources`` ({name: [(line number, shape)]}) hold the same run of SAME_SHAPE_RUN line
    shapes. Only lines that hold a name, number, string or substitution count (not lines of
    punctuation and keywords alone, such as closing brackets or ``try:``, nor declarations:
    ``NAME = 3``, ``field: int = 0``), and a run of a single shape (a table) is no duplicate."""
    seen, found = {}, {}
    for name, shapes in sources.items():
        lines = [(number, shape) for number, shape in shapes
                 if PLACEHOLDERS & set(shape.split()) and not DECLARATION.fullmatch(shape)]
        for start in range(len(lines) - SAME_SHAPE_RUN + 1):
            window = lines[start:start + SAME_SHAPE_RUN]
            run = tuple(shape for _, shape in window)
            if len(set(run)) == 1:
                continue
            place = (name, window[0][0], window[-1][0])
            for other in seen.get(run, []):
                if other[0] != name or other[2] < place[1]:  # in one file, two runs that do not overlap
                    found.setdefault((other[0], name),
                                     f"{other[0]}:{other[1]}-{other[2]} ~ {name}:{place[1]}-{place[2]}")
            seen.setdefault(run, []).append(place)
    return sorted(found.values())


def scanned_sources():
    """{path: line shapes} of kingen's Python modules and of the C files and C templates under
    kingen/ and templates/, vendored code aside."""
    sources = {}
    for folder in (PACKAGE, PACKAGE.parent / "templates"):
        for path in sorted(folder.rglob("*")):
            name = str(path.relative_to(PACKAGE.parent))
            if "vendor" in path.relative_to(folder).parts or not path.is_file():
                continue
            if path.suffix == ".py":
                sources[name] = python_shapes(path.read_text())
            elif path.name.endswith(C_SUFFIXES):
                sources[name] = c_shapes(path.read_text())
    return sources


def test_no_code_stands_twice():
    pairs = same_shape_runs(scanned_sources())
    assert not pairs, "the same run of lines (alike but for names and values) stands in two places: give it one " \
                      "home:\n" + "\n".join(pairs)


def test_a_planted_duplicate_fails_the_duplication_test():
    module = '''
import os
from pathlib import Path

LIMIT = 3
"""A declaration."""


def first(path):
    """A docstring."""
    if path is not None:  # a comment
        try:
            check(path, LIMIT)
        except KingenError as error:
            raise click.BadParameter(str(error)) from None
    return path
'''
    renamed = module.replace("first", "second").replace("path", "value").replace("check", "verify")
    assert same_shape_runs({"a.py": python_shapes(module), "b.py": python_shapes(renamed)}) == [
        "a.py:9-16 ~ b.py:9-16"]
    shorter = renamed.replace("    return value\n", "")
    assert same_shape_runs({"a.py": python_shapes(module), "b.py": python_shapes(shorter)}) == []
    c = "static int f(int x)\n{\n    /* c */\n    int y = x + 1;\n    y *= scale;\n    if (y > 3)\n" \
        "        y = 3;\n    return y;\n}\n"
    template = c.replace("f(", "g(").replace("scale", "{{ scale }}").replace("/* c */", "{# jinja #}")
    assert same_shape_runs({"a.c": c_shapes(c), "b.c.j2": c_shapes(template)}) == ["a.c:1-8 ~ b.c.j2:1-8"]


NAME_LIMB_TYPES = ("kingen/robot/limbs/__init__.py", "kingen/robot/layouts.py")
"""The modules outside the limb models (each registered model's module, their base and their
template partials) that may name a limb type, at most two: the models' registry, and the layouts,
the robot file's tags that expand into limbs of one model (``layout: {type: stewart_gough}``).
Everything else asks the model."""
C_PROSE = re.compile(r"/\*.*?\*/|//[^\n]*|\{#.*?#\}", re.DOTALL)


def limb_type_names(text, kind, models):
    """Where ``text`` (a Python module, kind 'py', or C or a C template, kind 'c') names one of
    the limb ``models`` (the registry: tag -> class): a Python string equal to a tag or a name
    equal to a class's; in C, outside comments, a tag, its plural or kingen_<tag>(s) as a word.
    [(line, word)]."""
    if kind == "c":
        code = C_PROSE.sub(lambda match: "\n" * match.group(0).count("\n"), text)
        word = re.compile(r"\b(?:kingen_)?(?:%s)s?\b" % "|".join(map(re.escape, models)))
        return [(code[:found.start()].count("\n") + 1, found.group(0)) for found in word.finditer(code)]
    classes = {cls.__name__ for cls in models.values()}
    found = []
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type == tokenize.NAME and token.string in classes:
            found.append((token.start[0], token.string))
        elif token.type == tokenize.STRING and token.string.strip("'\"") in models \
                and ast.literal_eval(token.string) in models:
            found.append((token.start[0], token.string))
    return found


def limb_type_naming_modules(models):
    """{path: [(line, word)]} of kingen's Python modules, C files and C templates outside the limb
    models (the ``models``' own modules, their base, their partials) that name a limb type
    (limb_type_names)."""
    from kingen.robot.limbs import LimbModel, partial_path

    root = PACKAGE.parent
    own = {Path(sys.modules[cls.__module__].__file__).resolve() for cls in (LimbModel, *models.values())}
    own |= {partial_path(cls).resolve() for cls in models.values()}
    found = {}
    for path in sorted([*PACKAGE.rglob("*"), *(root / "templates").rglob("*")]):
        if not path.is_file() or path.resolve() in own:
            continue
        kind = "py" if path.suffix == ".py" else "c" if path.name.endswith(C_SUFFIXES) else None
        names = limb_type_names(path.read_text(), kind, models) if kind else []
        if names:
            found[str(path.relative_to(root))] = names
    return found


def test_outside_the_limb_models_at_most_two_modules_name_a_limb_type():
    from kingen.robot.limbs import MODELS

    assert len(NAME_LIMB_TYPES) <= 2
    named = {path: names for path, names in limb_type_naming_modules(MODELS).items() if path not in NAME_LIMB_TYPES}
    assert named == {}, "these modules name a limb type: ask the limb model (kingen/robot/limbs/base.py) instead"


def test_a_planted_limb_type_fails_the_limb_type_test():
    from kingen.robot.limbs import MODELS

    python = 'closed = robot.models == ("rail",)\nfrom .limbs import Crank  # a crank\nwords = "three rails"\n'
    assert limb_type_names(python, "py", MODELS) == [(1, '"rail"'), (2, "Crank")]
    c = "/* three rails */\nconst kingen_rail *rail = &kingen_data->rails[0]; // a rail\n{# legs #}{{ crank_length }}\n"
    assert limb_type_names(c, "c", MODELS) == [(2, "kingen_rail"), (2, "rail"), (2, "rails")]
