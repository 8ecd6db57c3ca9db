"""Mutants of kingen's C templates (jinja2 text that becomes C): one small change each, in
the C itself, never inside a jinja2 tag (``{{ }}``, ``{% %}``, ``{# #}``), a C comment or a
string literal.

Operators (``+ -``, ``* /``, ``&& ||``), comparisons (``< <=``, ``> >=``, ``== !=``),
constants (an integer n becomes n + 1; a literal with an exponent is scaled by ten, so a
tolerance 1e-5 becomes 1e-4; any other floating literal f becomes f + 1) and dropped
statements (an expression statement on one line, ``x = ...;`` or ``call(...);``, removed).
The templates' style writes binary operators between spaces, so `` * `` is a product and
``*p`` a pointer, never mutated.
"""

import re
from dataclasses import dataclass

_SWAPS = {" + ": " - ", " - ": " + ", " * ": " / ", " / ": " * ", " && ": " || ", " || ": " && ",
          " <= ": " < ", " < ": " <= ", " >= ": " > ", " > ": " >= ", " == ": " != ", " != ": " == "}
_OPERATOR = re.compile(r" (?:<=|>=|==|!=|&&|\|\||[-+*/<>]) ")
_NUMBER = re.compile(r"(?<![\w.])(\d+\.\d*(?:[eE][-+]?\d+)?|\d+[eE][-+]?\d+|\.\d+(?:[eE][-+]?\d+)?|\d+)(?![\w.])")
_TYPES = ("double ", "int ", "const ", "static ", "unsigned ", "char ", "long ", "float ", "typedef ", "return",
          "struct ", "DllExport ", "#", "case ", "default", "break", "else", "}", "{")
_STATEMENT = re.compile(r"^\s*[A-Za-z_][\w\[\]\->.*]*(?:\s*(?:[-+*/]?=)|\s*\().*;\s*$")


@dataclass(frozen=True)
class CMutant:
    path: str
    line: int  # 1-based
    column: int  # 0-based, in the line
    original: str
    replacement: str

    @property
    def key(self):
        return f"{self.path}:{self.line}:{self.column}:{self.original.strip()}->{self.replacement.strip() or 'drop'}"

    def apply(self, text):
        lines = text.split("\n")
        line = lines[self.line - 1]
        assert line[self.column:self.column + len(self.original)] == self.original, self.key
        lines[self.line - 1] = line[:self.column] + self.replacement + line[self.column + len(self.original):]
        return "\n".join(lines)


def _code_spans(text):
    """Per line, a mask (list of bools) of the characters that are C code: not in a jinja2
    tag, a C comment (also across lines) or a string or character literal."""
    masks, in_comment, in_tag = [], False, None
    for line in text.split("\n"):
        mask = [False] * len(line)
        i = 0
        while i < len(line):
            if in_tag:
                end = line.find(in_tag, i)
                if end < 0:
                    i = len(line)
                    break
                i, in_tag = end + 2, None
                continue
            if in_comment:
                end = line.find("*/", i)
                if end < 0:
                    i = len(line)
                    break
                i, in_comment = end + 2, False
                continue
            two = line[i:i + 2]
            if two in ("{{", "{%", "{#"):
                in_tag = {"{{": "}}", "{%": "%}", "{#": "#}"}[two]
                i += 2
            elif two == "/*":
                in_comment, i = True, i + 2
            elif two == "//":
                break
            elif line[i] in "\"'":
                quote, i = line[i], i + 1
                while i < len(line) and line[i] != quote:
                    i += 2 if line[i] == "\\" else 1
                i += 1
            else:
                mask[i] = True
                i += 1
        masks.append(mask)
    return masks


def _all_code(mask, start, end):
    return end <= len(mask) and all(mask[start:end])


def _scaled(literal):
    if re.search(r"[eE]", literal):
        mantissa, exponent = re.split(r"[eE]", literal)
        return f"{mantissa}e{int(exponent) + 1}"
    if "." in literal:
        return f"({literal} + 1.0)"
    return str(int(literal) + 1)


def c_mutants(path, text):
    """Every mutant of the template ``text`` (its repository ``path`` names them)."""
    mutants = []
    for number, (line, mask) in enumerate(zip(text.split("\n"), _code_spans(text)), 1):
        if line.lstrip().startswith("#include") or line.lstrip().startswith("#error"):
            continue
        for match in _OPERATOR.finditer(line):
            if _all_code(mask, match.start(), match.end()):
                mutants.append(CMutant(path, number, match.start(), match.group(), _SWAPS[match.group()]))
        for match in _NUMBER.finditer(line):
            if _all_code(mask, match.start(), match.end()) and not line[:match.start()].rstrip().endswith("["):
                mutants.append(CMutant(path, number, match.start(), match.group(), _scaled(match.group())))
        stripped = line.strip()
        code = "".join(ch for ch, is_code in zip(line, mask) if is_code).strip()
        if (code == stripped and _STATEMENT.match(line) and not stripped.startswith(_TYPES)
                and "{%" not in line and "{{" not in line):
            indent = len(line) - len(line.lstrip())
            mutants.append(CMutant(path, number, indent, line[indent:], ";"))
    return mutants
