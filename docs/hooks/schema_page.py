"""MkDocs hook: the robot-file schema page, generated from kingen's pydantic models.

docs/reference/robot-file.md holds the marker ``<!-- robot-file-schema -->``; this hook
replaces it with one table per schema object, walked from
:func:`kingen.robot.model.robot_file_schema` (the top level, the registered limb models, the
layouts, and the ``optimize:`` section of :mod:`kingen.robot.design_schema`). Each field:
its name, type, default, range and checks, and description (the attribute docstring that
follows the field in the model's source, from the class or the one it inherits the field
from). Nothing here is written by hand but the words for the shared validators below, so
the page follows the models.
"""

import ast
import inspect
import re
import sys
import textwrap
import typing
from pathlib import Path

import annotated_types
from markdown_parts import piped, replaced_marker

MARKER = "<!-- robot-file-schema -->"
PAGE = "reference/robot-file.md"


def on_config(config):
    # Document the models of this checkout, whatever kingen an environment has installed.
    root = str(Path(config.config_file_path).resolve().parent)
    if root not in sys.path:
        sys.path.insert(0, root)
    return config


def on_page_markdown(markdown, page, config, files):
    return replaced_marker(markdown, page, PAGE, MARKER, schema_markdown)


# -- what the page says about validators ----------------------------------------------------

def _validator_words():
    from kingen.robot import schema

    return {
        "_check_pose": (f"x, y, z within ±{schema.MAX_MM:g} mm; roll, pitch, yaw within "
                        f"±{schema.MAX_DEGREES:g}°"),
        "_check_travel": "lower limit below upper limit",
        "_check_unit": (f"a unit vector (norm within {schema.UNIT_TOLERANCE:g} of 1; "
                        "normalised exactly)"),
        "_check_non_negative": "no entry negative",
        "_check_c_names": ("the names every host makes from it must not collide with a name C "
                           "or that host reserves"),
        "_check_calibratable": "keys: the parameters this model can calibrate (below)",
        "_ordered": "`bounds`: lower bound below upper bound",
        "_constricted": "`c1 + c2` must exceed 4 (the constriction factor)",
    }


def _validator_text(function, words):
    name = getattr(function, "__name__", str(function))
    if name in words:
        return words[name]
    doc = inspect.getdoc(function)
    return doc.split("\n\n")[0].replace("\n", " ") if doc else f"checked by `{name}`"


# -- attribute docstrings ---------------------------------------------------------------------

def _attribute_docs(cls):
    """{field: docstring} of the string literals that follow annotated assignments in the
    class body of ``cls`` and of the classes it inherits from (the nearest wins)."""
    docs = {}
    for klass in reversed(cls.__mro__):
        if klass.__module__.split(".")[0] != "kingen":
            continue
        try:
            tree = ast.parse(textwrap.dedent(inspect.getsource(klass)))
        except (OSError, TypeError):
            continue
        body = tree.body[0].body
        for statement, following in zip(body, body[1:]):
            if (isinstance(statement, ast.AnnAssign) and isinstance(statement.target, ast.Name)
                    and isinstance(following, ast.Expr) and isinstance(following.value, ast.Constant)
                    and isinstance(following.value.value, str)):
                docs[statement.target.id] = _markdown(" ".join(inspect.cleandoc(following.value.value).split()))
    return docs


def _class_doc(cls):
    doc = cls.__dict__.get("__doc__")
    return _markdown(" ".join(inspect.cleandoc(doc).split())) if doc else ""


def _markdown(text):
    """reStructuredText's ``literal`` and :role:`target` as Markdown code."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", text)
    return text.replace("``", "`")


def _anchor(text):
    return re.sub(r"[^a-z0-9_]+", "-", text.lower()).strip("-")


# -- types and their constraints ----------------------------------------------------------------

def _is_model(annotation):
    from pydantic import BaseModel

    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def _bounds(metadata):
    """'0.001 to 1e+06', '> 0', ... from annotated_types metadata (and FieldInfo's)."""
    lower = upper = None
    words, length = [], {}
    for item in metadata:
        for attribute, kind in (("ge", "ge"), ("gt", "gt"), ("le", "le"), ("lt", "lt")):
            value = getattr(item, attribute, None)
            if value is not None and isinstance(item, (annotated_types.BaseMetadata,)):
                if kind in ("ge", "gt"):
                    lower = (kind, value)
                else:
                    upper = (kind, value)
        if isinstance(item, annotated_types.MinLen):
            length["min"] = item.min_length
        if isinstance(item, annotated_types.MaxLen):
            length["max"] = item.max_length
        pattern = getattr(item, "pattern", None)
        if pattern:
            words.append(f"matches `{pattern}`")
    if lower and upper and lower[0] == "ge" and upper[0] == "le":
        words.insert(0, f"{lower[1]:g} to {upper[1]:g}")
    else:
        if lower:
            words.insert(0, f"{'≥' if lower[0] == 'ge' else '>'} {lower[1]:g}")
        if upper:
            words.insert(1 if lower else 0, f"{'≤' if upper[0] == 'le' else '<'} {upper[1]:g}")
    return words, length


def _length_words(length):
    low, high = length.get("min"), length.get("max")
    if low is not None and low == high:
        return f"exactly {low}"
    if low is not None and high is not None:
        return f"{low} to {high}"
    if low is not None:
        return f"at least {low}"
    if high is not None:
        return f"at most {high}"
    return ""


def _unwrap(annotation):
    """(bare type, its Annotated metadata)."""
    metadata = []
    while typing.get_origin(annotation) is typing.Annotated:
        annotation, *extra = typing.get_args(annotation)
        metadata = [*extra, *metadata]
    flat = []
    for item in metadata:
        flat.append(item)
        flat.extend(getattr(item, "metadata", ()) or ())  # a FieldInfo's own constraints
    return annotation, flat


class Walker:
    """Renders types as words and collects the schema objects (models) to give a table each."""

    def __init__(self):
        self.words = _validator_words()
        self.sections = []  # (anchor, title, model, intro)
        self.anchors = {}

    def model_link(self, model, anchor, title, label=None):
        if model not in self.anchors:
            self.anchors[model] = anchor
            self.sections.append((anchor, title, model, ""))
        return f"[{label or _heading(title)}](#{self.anchors[model]})"

    def describe(self, annotation, metadata, path):
        """(type words, [constraint words]) of a field's type at YAML path ``path``."""
        bare, inner = _unwrap(annotation)
        metadata = [*metadata, *inner]
        checks = [_validator_text(item.func, self.words) for item in metadata
                  if type(item).__name__ == "AfterValidator"]
        bounds, length = _bounds(metadata)
        origin, args = typing.get_origin(bare), typing.get_args(bare)
        discriminator = next((getattr(item, "discriminator", None) for item in metadata
                              if getattr(item, "discriminator", None)), None)

        if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
            options = [arg for arg in args if arg is not type(None)]
            if len(options) == 1:
                text, more = self.describe(options[0], metadata, path)
                return text, [*bounds, *checks, *more] if not _is_model(options[0]) else [*checks, *more]
            if discriminator:
                links = []
                for option in options:
                    option_bare, _ = _unwrap(option)
                    tag = typing.get_args(option_bare.model_fields[discriminator].annotation)[0]
                    links.append(self.model_link(option_bare, _anchor(f"{path}-{tag}"),
                                                 f"{path}: {discriminator}: {tag}", f"`{tag}`"))
                return f"one of (by `{discriminator}`): " + ", ".join(links), checks
            texts = [self.describe(option, [], path)[0] for option in options]
            return " or ".join(texts), [*bounds, *checks]
        if origin is typing.Literal:
            if len(args) == 1:
                return f"`{args[0]}`", checks
            return "one of " + ", ".join(f"`{value}`" for value in args), checks
        if origin is list:
            item_text, item_checks = self.describe(args[0], [], path + "[]")
            count = _length_words(length)
            words = [f"each {word}" for word in item_checks]
            return f"list ({count}) of {item_text}" if count else f"list of {item_text}", [*words, *checks]
        if origin is dict:
            key_text, key_checks = self.describe(args[0], [], path)
            value_text, value_checks = self.describe(args[1], [], path)
            words = [*(f"keys: {word}" for word in key_checks), *(f"values: {word}" for word in value_checks)]
            return f"mapping of {key_text} to {value_text}", [*words, *checks]
        if _is_model(bare):
            return self.model_link(bare, _anchor(path), path), checks
        names = {float: "numbers" if path.endswith("[]") else "number", int: "integer", str: "string",
                 bool: "true or false"}
        return names.get(bare, getattr(bare, "__name__", str(bare))), [*bounds, *checks]


def _heading(title):
    """'limbs[]: model: leg' -> '`limbs` entry with `model: leg`'."""
    path, _, tag = title.partition(": ")
    words = f"`{path[:-2]}` entry" if path.endswith("[]") else f"`{path}`"
    return f"{words} with `{tag}`" if tag else words


def _default(field):
    from pydantic_core import PydanticUndefined

    if field.is_required():
        return "required"
    value = field.default
    if value is PydanticUndefined and field.default_factory is not None:
        value = field.default_factory()
    if value is None:
        return "absent"
    if _is_model(type(value)):
        return "all defaults"
    if isinstance(value, (dict, list)) and not value:
        return "empty"
    if isinstance(value, str):
        return f"`{value}`"
    return f"`{value!r}`"


def _cell(text):
    """A table cell: pipes escaped outside code spans (inside them the table reads them as text)."""
    return piped(str(text).replace("\n", " "))


def _model_checks(model, words):
    """Words for the model's own validators (on fields and on the whole object)."""
    decorators = model.__pydantic_decorators__
    found = []
    for name, decorator in {**decorators.field_validators, **decorators.model_validators}.items():
        found.append(_validator_text(decorator.func, words))
    return found


def schema_markdown():
    from kingen.robot.file_schema import robot_file_schema

    walker = Walker()
    walker.model_link(robot_file_schema(), "top-level", "top level")
    lines = []
    done = 0
    while done < len(walker.sections):  # sections grow as the tables name more objects
        anchor, title, model, intro = walker.sections[done]
        done += 1
        docs = _attribute_docs(model)
        rows = []
        for name, field in model.model_fields.items():
            path = name if anchor == "top-level" else f"{title.split(':')[0]}.{name}"
            path = path.replace("[].", ".")
            type_text, constraints = walker.describe(field.annotation, field.metadata, path)
            rows.append((f"`{name}`", type_text, _default(field), "; ".join(constraints) or "",
                         _markdown(field.description or docs.get(name, ""))))
        heading = "Top level" if anchor == "top-level" else _heading(title)
        lines += [f"## {heading} {{#{anchor}}}", ""]
        summary = _class_doc(model)
        if summary and anchor != "top-level":
            lines += [summary, ""]
        calibratable = getattr(model, "calibratable", None)
        if isinstance(calibratable, dict) and calibratable:
            lines += ["Calibratable parameters (`calibrate:` keys): "
                      + ", ".join(f"`{key}` ({unit})" for key, unit in calibratable.items()) + ".", ""]
        checks = [word for word in _model_checks(model, walker.words)
                  if not word.startswith("keys: the parameters")]
        if checks:
            lines += ["Also checked: " + "; ".join(checks) + ".", ""]
        lines += ["| field | type | default | range and checks | description |",
                  "| --- | --- | --- | --- | --- |"]
        lines += ["| " + " | ".join(_cell(cell) for cell in row) + " |" for row in rows]
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":  # python docs/hooks/schema_page.py: print the generated tables
    print(schema_markdown())
