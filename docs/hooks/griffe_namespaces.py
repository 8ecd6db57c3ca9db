"""Griffe extension for the API page: kingen's folders without ``__init__.py``.

Some of kingen's packages (``kingen.robot``, ``kingen.kinematics``, ...) are folders without an
``__init__.py``, which Python imports as namespace packages inside kingen. Griffe, which reads
the source for mkdocstrings, skips such folders inside a regular package, so the API page
could not name ``kingen.robot.limbs.base.LimbModel``. When ``kingen/__init__.py`` has been
read and before its submodules are, this extension adds an empty module for each such folder,
so that griffe reads the modules inside it as it reads the others.
"""

from pathlib import Path

import griffe


class NamespaceFolders(griffe.Extension):
    def on_module_members(self, *, mod, **kwargs):
        # Fired when kingen/__init__.py has been read, before the loader reads the submodules.
        if mod.path != "kingen" or not mod.filepath:
            return
        for child in sorted(Path(mod.filepath).parent.iterdir()):
            if (child.is_dir() and not (child / "__init__.py").exists() and child.name.isidentifier()
                    and any(child.glob("*.py")) and child.name not in mod.members):
                mod.set_member(child.name, griffe.Module(
                    child.name, filepath=[child], lines_collection=mod.lines_collection,
                    modules_collection=mod.modules_collection))
