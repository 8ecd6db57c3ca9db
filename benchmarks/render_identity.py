"""Render every shipped robot for the DELMIA, C (library and package) and LinuxCNC hosts into a
folder (argument 1), one file per robot, host and output; compare two such folders with
`diff -r` to show that a change to the shared templates leaves the other robots' sources
byte-identical. Prints what it rendered and what each host refused."""

import sys
from pathlib import Path

from kingen.errors import KingenError
from kingen.hosts.c import package as c_package
from kingen.hosts.c import render as c_render
from kingen.hosts.delmia import render as delmia_render
from kingen.hosts.linuxcnc import render as linuxcnc_render
from kingen.robot.model import load_robot

HOSTS = {"delmia": delmia_render.render, "c": c_render.render, "c-package": c_package.render_package,
         "linuxcnc": linuxcnc_render.render}


def main(folder):
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted(Path("robots").glob("*.yaml")):
        robot = load_robot(path)
        for host, render in HOSTS.items():
            try:
                files = render(robot)
            except KingenError as error:
                print(f"{path.stem} {host}: refused: {error}")
                continue
            for name, text in files.items():
                (out / f"{path.stem}-{host}-{name.replace('/', '-')}").write_text(text)
            print(f"{path.stem} {host}: {len(files)} file(s)")


if __name__ == "__main__":
    main(sys.argv[1])
