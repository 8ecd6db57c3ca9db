"""What the generated reference pages' hooks (schema_page.py, commands_page.py) share: a page's
marker replaced by generated Markdown, and a table cell's pipes escaped. Not a hook itself:
MkDocs puts the hooks' folder on the path while it loads them."""


def replaced_marker(markdown, page, path, marker, render):
    """``markdown`` of ``page`` with ``marker`` replaced by ``render()`` when the page is ``path``
    (its other pages as they are); ValueError when that page has lost its marker."""
    if page.file.src_uri != path:
        return markdown
    if marker not in markdown:
        raise ValueError(f"{path} has lost its marker {marker}")
    return markdown.replace(marker, render())


def piped(text):
    """``text`` (one line) with its pipes escaped outside code spans: inside them a table reads
    them as text."""
    parts = text.split("`")
    return "`".join(part if index % 2 else part.replace("|", "\\|") for index, part in enumerate(parts))
