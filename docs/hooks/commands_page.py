"""MkDocs hook: the command reference, generated from kingen's click definitions.

docs/reference/commands.md holds the marker ``<!-- kingen-commands -->``; this hook replaces
it with one section per command, ``kingen`` first and then its subcommands in name order, as
``kingen COMMAND --help`` prints them: the command's help, its usage, and one table row per
option whose left cell is the option with its metavar and whose right cell is its help with
the same bracketed notes ``--help`` adds (default, environment variable, range). A group lists
its subcommands, each with the first sentence of its help, whole. Text from the definitions is
escaped for Markdown and HTML outside its code spans, so ``build/<name>`` reads as written.
"""

import inspect
import re

from markdown_parts import piped, replaced_marker

MARKER = "<!-- kingen-commands -->"
PAGE = "reference/commands.md"
PROG = "kingen"
# A sentence ends at . ? or ! (a closing bracket or quote may follow) before a capital letter.
SENTENCE_END = re.compile(r"(?<=[.?!])[)\"']?\s+(?=[A-Z`])")


def on_page_markdown(markdown, page, config, files):
    return replaced_marker(markdown, page, PAGE, MARKER, commands_markdown)


# -- text --------------------------------------------------------------------------------------

def escape(text):
    """``text`` as Markdown that shows it as written: outside code spans, HTML's ``& < >``
    become entities and Markdown's ``\\ * _ [ ]`` are backslash-escaped; code spans are kept
    (Markdown shows their insides as written)."""
    parts = text.split("`")
    if len(parts) % 2 == 0:  # an unpaired backtick: no code spans
        parts = [text.replace("`", "\\`")]
    for index in range(0, len(parts), 2):
        plain = parts[index].replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        parts[index] = re.sub(r"([\\*_\[\]])", r"\\\1", plain)
    return "`".join(parts)


def paragraph(text):
    """``text`` escaped as one Markdown paragraph: also what would open a heading, quote, list
    or thematic break where it starts is escaped."""
    text = escape(text)
    number = re.match(r"\d+(?=[.)])", text)  # "1. " opens a numbered list: its point escaped
    if number:
        return text[:number.end()] + "\\" + text[number.end():]
    return "\\" + text if re.match(r"[#>+-]", text) else text


def cell(text):
    """``text`` escaped for one table cell: on one line, pipes outside code spans escaped."""
    return piped(escape(" ".join(text.split())))


def paragraphs(help_text):
    """The paragraphs of a click help text, each unwrapped to one line (click's ``\\b``
    no-rewrap markers dropped)."""
    text = inspect.cleandoc(help_text or "")
    return [" ".join(block.replace("\b", "").split()) for block in re.split(r"\n\s*\n", text) if block.strip()]


def summary(command):
    """A command's one-line summary: its ``short_help``, or the first sentence of its help,
    whole."""
    if command.short_help:
        return command.short_help
    first = paragraphs(command.help)
    return SENTENCE_END.split(first[0], maxsplit=1)[0] if first else "(no description)"


# -- pages -------------------------------------------------------------------------------------

def context(command, name, parent=None):
    """The click context ``--help`` would format ``command`` in (its context settings, such as
    ``-h``, applied)."""
    return command.context_class(command, info_name=name, parent=parent, **command.context_settings)


def subcommands(ctx):
    """The visible subcommands of the group in ``ctx``, in name order (none for a command)."""
    group = ctx.command
    if not hasattr(group, "list_commands"):
        return []
    found = (group.get_command(ctx, name) for name in group.list_commands(ctx))
    return sorted((command for command in found if command is not None and not command.hidden),
                  key=lambda command: command.name)


def usage(ctx):
    """The usage line ``--help`` prints, without its ``Usage:`` prefix."""
    formatter = ctx.make_formatter()
    formatter.write_usage(ctx.command_path, " ".join(ctx.command.collect_usage_pieces(ctx)), prefix="")
    return " ".join(formatter.getvalue().split())


def option_rows(ctx):
    """Table rows of the options ``--help`` lists: (option and metavar, help with its notes)."""
    records = (param.get_help_record(ctx) for param in ctx.command.get_params(ctx))
    return [f"| `{names}` | {cell(text)} |" for names, text in filter(None, records)]


def section(ctx, depth):
    """The Markdown lines of one command's section and its subcommands' sections."""
    path = ctx.command_path
    anchor = path.replace(" ", "-")
    lines = [f"{'#' * depth} {path} {{ #{anchor} data-toc-label='{ctx.info_name}' }}", ""]
    lines += [line for text in paragraphs(ctx.command.help) for line in (paragraph(text), "")]
    lines += ["**Usage:**", "", "```text", usage(ctx), "```", ""]
    rows = option_rows(ctx)
    if rows:
        lines += ["**Options:**", "", "| Option | Description |", "| --- | --- |", *rows, ""]
    children = [context(command, command.name, ctx) for command in subcommands(ctx)]
    if children:
        lines += ["**Subcommands:**", ""]
        lines += [f"- [{child.info_name}](#{child.command_path.replace(' ', '-')}): "
                  f"{escape(summary(child.command))}" for child in children]
        lines.append("")
    for child in children:
        lines += section(child, depth + 1)
    return lines


def commands_markdown():
    """The reference of ``kingen`` and every subcommand, as Markdown."""
    from kingen.cli import cli

    return "\n".join(section(context(cli, PROG), 2))
