"""Safe text: how user-supplied strings are emitted into generated files and terminals.

Every string that comes from a robot file (description, sources, names) or from the
file system (the robot file's name) and ends up in generated text passes through
one of these functions, chosen by the kind of file it lands in. Each guarantees that
the string cannot change the meaning of the text around it:

- ``c_text``: inside a C block comment or string of generated C: ASCII only, no
  comment delimiters, trigraphs, backslashes (line splices) or line breaks.
- ``one_line``: one line of plain text (makefile comments, BUILD.txt, terminal
  output, report files): no line breaks, control, bidi or other invisible characters.
- ``markdown``: a Markdown paragraph or table cell: ``one_line`` plus Markdown and
  HTML syntax escaped, so the text shows as typed and nothing is interpreted.

Characters that are replaced are written as ``<U+XXXX>``, so nothing is silently lost.
"""

import re
import unicodedata

_MARKDOWN_SPECIAL = re.compile(
    r"[\\`*\[\]|~]"                          # code, emphasis, links and images, table cells, strikethrough
    r"|(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])"    # emphasis: an underscore not inside a word
    r"|<(?=[A-Za-z/!?])"                      # HTML tags and autolinks
    r"|>"                                     # the end of such a tag (escaped only after one)
    r"|&(?=#?[A-Za-z0-9]+;)")                 # character references
_LINE_START_SPECIAL = re.compile(r"^(?:[#>+=:-]|[0-9]+[.)])")
"""What would open a heading, quote, list, definition or thematic break where a line starts."""


def _escaped(character):
    return f"<U+{ord(character):04X}>"


def unprintable(character):
    """True for characters that must never reach a file or terminal as themselves:
    control characters (C0, DEL, C1), line and paragraph separators, and format
    characters (bidi overrides and isolates, zero-width characters)."""
    return not character.isprintable() and character != " " or unicodedata.category(character) == "Cf"


def printable(text):
    """``text`` with every unprintable character written as ``<U+XXXX>`` (spacing kept):
    safe for a terminal, where escape sequences could otherwise recolour or rewrite it."""
    return "".join(_escaped(c) if unprintable(c) else c for c in str(text))


def one_line(text):
    """``text`` as one line: runs of whitespace become one space; every unprintable
    character becomes ``<U+XXXX>``."""
    return printable(" ".join(str(text).split()))


def shorten(text, width):
    """``text`` on one line (runs of whitespace become one space), cut to at most ``width``
    characters, the cut marked with '...'."""
    text = " ".join(text.split())
    return text if len(text) <= width else text[: width - 3] + "..."


def c_text(text):
    """``text`` safe inside a C block comment or a C string literal of generated code.

    ASCII printable only (others become ``<U+XXXX>``); ``*/`` and ``/*`` are broken
    up, ``??`` (trigraph introducer), backslashes and double quotes are replaced, so
    the text can neither end the comment or string nor splice lines."""
    text = one_line(text)
    text = "".join(c if " " <= c <= "~" else _escaped(c) for c in text)
    text = text.replace("\\", "<U+005C>").replace('"', "<U+0022>")
    while "??" in text:
        text = text.replace("??", "? ?")
    while "*/" in text or "/*" in text:
        text = text.replace("*/", "* /").replace("/*", "/ *")
    return text


def markdown(text):
    """``text`` as literal Markdown (no headings, lists, links, HTML, emphasis or table breaks),
    wherever on a line it lands, that reads as typed in a plain editor too: a backslash only
    before a character Markdown would read as syntax where it stands (``\\<b\\>``, ``a \\| b``,
    ``\\_x\\_``), none before ``(``, ``+`` or ``#`` inside a line (``(centroid)``, ``+Z``). A tag's
    ``>`` is escaped too, for renderers (Python-Markdown) that keep ``\\<`` as it is."""
    opened = False

    def escape(match):
        nonlocal opened
        if match.group(0) == ">":
            closing, opened = opened, False
            return "\\>" if closing else ">"
        opened = opened or match.group(0) == "<"
        return "\\" + match.group(0)

    text = _MARKDOWN_SPECIAL.sub(escape, one_line(text))
    return _LINE_START_SPECIAL.sub(lambda match: match.group(0)[:-1] + "\\" + match.group(0)[-1], text)


def xml_text(text):
    """``text`` with what XML 1.0 cannot hold (control characters other than tab and line
    breaks, lone surrogates, U+FFFE/U+FFFF) written as ``<U+XXXX>``; line breaks are kept."""
    return "".join(
        _escaped(c) if (c < " " and c not in "\t\n\r") or "\ud800" <= c <= "\udfff" or c in "\ufffe\uffff" else c
        for c in str(text)
    )


def finalizer(kind):
    """The jinja2 ``finalize`` for templates of ``kind`` ('c', 'markdown' or 'plain'):
    applied to every substituted string, so no template can forget it. Numbers pass
    unchanged; generated C fragments (identifiers, literals, prototypes) contain none
    of the characters ``c_text`` replaces, so they pass unchanged too."""
    escape = {"c": c_text, "markdown": one_line, "plain": one_line}[kind]

    def finalize(value):
        return escape(value) if isinstance(value, str) else value

    return finalize


def counted(count, noun, plural=None):
    """'1 posture', '8 postures': a count with its noun, plural (``plural``, else the noun and
    's') unless it is one."""
    return f"{count} {noun}" if count == 1 else f"{count} {plural or noun + 's'}"
