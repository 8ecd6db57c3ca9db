"""Reading a robot file: YAML 1.2 text to plain data, with the line of every field, within limits.

A robot file is a few kilobytes written by a person; anything far outside that is
refused before it can cost time or memory. Every refusal is one located
:class:`~kingen.errors.KingenError`. The limits, each checked before the step it protects:

- at most ``MAX_FILE_BYTES`` of UTF-8 text;
- at most ``MAX_DEPTH`` levels of nested collections (checked on the raw text for flow
  brackets, whose parsing is quadratic in depth, then on the parser's events);
- anchors and aliases are allowed, but each anchor is defined once (YAML 1.2 lets a later
  ``&a`` redefine an earlier one, which a reader of ``*a`` easily misses), the document
  they expand to has at most ``MAX_NODES`` nodes, and an alias may not refer to a
  collection that contains it;
- one document; keys are text and appear once per mapping; no tags;
- numbers follow YAML 1.2 (``031`` is 31, ``6:39`` is text, ``3.99413e2`` is a number);
- text holds no control, bidi or other invisible characters (they could disguise what a
  reviewer reads or reach a terminal), and is at most ``MAX_TEXT`` characters.
"""

import re

from ruamel.yaml import YAML
from ruamel.yaml.comments import CommentedMap, CommentedSeq
from ruamel.yaml.error import MarkedYAMLError, YAMLError
from ruamel.yaml.events import AliasEvent, CollectionEndEvent, CollectionStartEvent, MappingStartEvent, ScalarEvent

from ..errors import located
from ..runtime.file_gate import read_limited
from ..runtime.text import unprintable

MAX_FILE_BYTES = 1_000_000
MAX_DEPTH = 32
MAX_NODES = 100_000
MAX_TEXT = 4000
MAX_NUMBER = 1e300
"""Numbers beyond this magnitude are refused here; the schema sets the real ranges."""


def read_robot_file(path):
    """(data, lines) for the robot file at ``path``: plain dicts, lists, str, int, float,
    bool and None, and {field path tuple: 1-based line}. Raises KingenError."""
    shown = str(path)
    raw = read_limited(path, MAX_FILE_BYTES, "a robot file is a few kB")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise located(shown, None, None, f"not UTF-8 text ({error.reason} at byte {error.start})") from None
    _check_flow_depth(text, shown)
    yaml = YAML(typ="rt")
    yaml.allow_duplicate_keys = True  # refused with their path by _check_events
    try:
        _check_events(yaml.parse(text), shown)
        document = yaml.load(text)
    except MarkedYAMLError as error:
        raise _yaml_error(error, shown) from None
    except TypeError:  # ruamel hashing a key that is a list or a mapping ("? [a]: b")
        raise located(shown, None, None, "YAML: a key must be text, not a list or a mapping") from None
    except (YAMLError, ValueError, RecursionError) as error:
        problem = str(error).splitlines()[0]
        if "integer string conversion" in problem:
            problem = "a number with thousands of digits"
        raise located(shown, None, None, f"YAML syntax: {problem}") from None
    if not isinstance(document, CommentedMap):
        raise located(shown, None, None, "expected a mapping of robot fields at the top level")
    lines = {}
    return _plain(document, (), lines, shown, None), lines, raw


def _yaml_error(error, shown):
    mark = error.problem_mark or error.context_mark
    line = mark.line + 1 if mark is not None else None
    problem = " ".join((error.problem or error.context or "syntax error").split())
    duplicate = re.match(r'found duplicate key "(.*?)"', problem)
    if duplicate:
        return located(shown, line, duplicate.group(1), "duplicate key")
    return located(shown, line, None, f"YAML syntax: {problem}")


def _check_flow_depth(text, shown):
    """Nesting of flow brackets ([ and {) outside quotes and comments, on the raw text."""
    depth, line, quote, comment, previous = 0, 1, None, False, "\n"
    for character in text:
        if character == "\n":
            line += 1
            comment = False
        elif comment:
            pass
        elif quote is not None:
            if character == quote and not (quote == '"' and previous == "\\"):
                quote = None
        elif character in "'\"" and previous in " \t\n[{,:":
            quote = character
        elif character == "#" and previous in " \t\n":
            comment = True
        elif character in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                raise located(shown, line, None, f"nested deeper than {MAX_DEPTH} levels")
        elif character in "]}":
            depth = max(depth - 1, 0)
        previous = "" if previous == "\\" and character == "\\" else character


_NON_TEXT = re.compile(
    r"~|null|Null|NULL|true|True|TRUE|false|False|FALSE|[-+]?[0-9_]+|0o[0-7]+|0x[0-9a-fA-F]+"
    r"|[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?|[-+]?\.(inf|Inf|INF)|\.(nan|NaN|NAN)|")
"""Plain scalars that YAML 1.2 reads as null, booleans or numbers: as keys they differ from
the same characters quoted (``1:`` and ``"1":`` are two keys); every other key is text."""


class _Collection:
    """A mapping or sequence open in the event stream: its path, expanded size and keys."""

    def __init__(self, path, anchor, mapping):
        self.path, self.anchor, self.mapping = path, anchor, mapping
        self.size, self.items, self.keys, self.key = 1, 0, set(), None

    def child_path(self):
        """The field path of the node that starts now."""
        if not self.mapping:
            return self.path + (self.items,)
        return self.path if self.key is None else self.path + (self.key,)

    def completed(self, event, shown, line):
        """Account for a direct child node that has just been read (a key or a value)."""
        if not self.mapping:
            self.items += 1
        elif self.key is not None:
            self.key = None
        elif isinstance(event, ScalarEvent):
            plain_non_text = event.style in (None, "") and _NON_TEXT.fullmatch(event.value)
            identity = ("not text", event.value) if plain_non_text else event.value
            if identity in self.keys:
                raise located(shown, line, dotted(self.path + (event.value,)), "duplicate key")
            self.keys.add(identity)
            self.key = event.value
        else:
            self.key = "?"


def _check_events(events, shown):
    """Depth, expanded size, duplicate keys and anchors from the parser's events, before
    anything is built (so ruamel's warnings about them never reach stderr)."""
    sizes = {}
    anchors = {}
    stack = []
    for event in events:
        line = event.start_mark.line + 1
        if getattr(event, "anchor", None) and not isinstance(event, AliasEvent):
            if event.anchor in anchors:
                path = stack[-1].child_path() if stack else ()
                raise located(shown, line, dotted(path), f"anchor &{event.anchor} is defined again (first on line "
                                                         f"{anchors[event.anchor]}); give each anchor its own name")
            anchors[event.anchor] = line
        if isinstance(event, CollectionStartEvent):
            path = stack[-1].child_path() if stack else ()
            stack.append(_Collection(path, event.anchor, isinstance(event, MappingStartEvent)))
            if len(stack) > MAX_DEPTH:
                raise located(shown, line, None, f"nested deeper than {MAX_DEPTH} levels")
            continue
        if isinstance(event, AliasEvent):
            if event.anchor not in sizes:
                raise located(shown, line, None, f"alias *{event.anchor} refers to a collection that contains it")
            count = sizes[event.anchor]
        elif isinstance(event, ScalarEvent):
            count = 1
            if event.anchor:
                sizes[event.anchor] = 1
        elif isinstance(event, CollectionEndEvent):
            finished = stack.pop()
            if finished.anchor:
                sizes[finished.anchor] = finished.size
            count = finished.size
        else:
            continue
        if stack:
            stack[-1].size += count
            if sum(entry.size for entry in stack) > MAX_NODES:
                raise located(shown, line, None, f"expands to more than {MAX_NODES} values (through aliases?)")
            stack[-1].completed(event, shown, line)


def _plain(node, path, lines, shown, line):
    """The plain-data copy of a loaded node; records lines and refuses what is not data."""
    if _tag(node):
        raise located(shown, line, dotted(path), f"YAML tag {_tag(node)} is not supported")
    if isinstance(node, CommentedMap):
        result = {}
        for key, value in node.items():
            key_line = node.lc.key(key)[0] + 1
            if not isinstance(key, str):
                raise located(shown, key_line, dotted(path), f"key {key!r} is not a field name")
            _check_text(key, path, shown, key_line)
            lines[path + (key,)] = key_line
            result[key] = _plain(value, path + (key,), lines, shown, key_line)
        return result
    if isinstance(node, CommentedSeq):
        result = []
        for index, value in enumerate(node):
            item_line = node.lc.item(index)[0] + 1
            lines[path + (index,)] = item_line
            result.append(_plain(value, path + (index,), lines, shown, item_line))
        return result
    if node is None or isinstance(node, bool):
        return node
    if isinstance(node, int):
        if abs(node) > MAX_NUMBER:
            raise located(shown, line, dotted(path), "number out of range")
        return int(node)
    if isinstance(node, float):
        return float(node)
    if isinstance(node, str):
        _check_text(node, path, shown, line)
        return str(node)
    raise located(shown, line, dotted(path), "expected a number, text, list or mapping "
                                              "(tags, dates and other YAML types are not supported)")


def _tag(node):
    tag = getattr(node, "tag", None)
    value = getattr(tag, "value", tag)
    return value if isinstance(value, str) and not value.startswith("tag:yaml.org,2002:") else None


def _check_text(text, path, shown, line):
    if len(text) > MAX_TEXT:
        raise located(shown, line, dotted(path), f"text longer than {MAX_TEXT} characters")
    for character in text:
        if unprintable(character) and character not in "\n\t":
            raise located(shown, line, dotted(path),
                          f"contains the invisible or control character U+{ord(character):04X}")


def dotted(path):
    """('limbs', 2, 'link_length') -> 'limbs[2].link_length'."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text or None

