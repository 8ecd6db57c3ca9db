"""What `pip install .` (not editable) installs: every package of kingen and every file it reads
at run time (templates, C sources, robots, vendored files), as pyproject.toml lists them."""

import fnmatch
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def folder_of(package):
    """The source folder of ``package`` under pyproject's package-dir mapping."""
    for prefix, folder in sorted(SETUPTOOLS["package-dir"].items(), key=lambda item: -len(item[0])):
        if package == prefix or package.startswith(prefix + "."):
            return ROOT / folder / Path(*package[len(prefix):].split(".")[1:])
    return ROOT / Path(*package.split("."))


def test_every_package_is_listed():
    found = {".".join(path.parent.relative_to(ROOT).parts) for path in (ROOT / "kingen").rglob("__init__.py")}
    assert found - set(SETUPTOOLS["packages"]) == set()


def test_every_data_file_is_installed():
    missed = []
    for package in SETUPTOOLS["packages"]:
        folder = folder_of(package)
        patterns = SETUPTOOLS["package-data"].get(package, [])
        for path in folder.rglob("*"):
            relative = path.relative_to(folder)
            if (not path.is_file() or path.suffix in (".py", ".pyc") or "__pycache__" in relative.parts
                    or (relative.parts[0] != relative.name and (folder / relative.parts[0] / "__init__.py").exists())):
                continue
            if not any(fnmatch.fnmatch(str(relative), pattern) for pattern in patterns):
                missed.append(f"{package}: {relative}")
    assert missed == []
