"""``kingen view``: the robot drawn in 3D in one self-contained HTML page (kingen.view)."""

from pathlib import Path

import click

from .common import ROBOT, _out_folder, _pose, cli, load_model, say


@cli.command()
@ROBOT
@click.option("--pose", nargs=6, type=float, metavar="X Y Z ROLL PITCH YAW", callback=_pose, default=None,
              help="The pose shown first (mm, degrees) [default: the verification home]; a machine with task "
                   "coordinates takes the pose its constraints give for them.")
@click.option("--posture", type=click.IntRange(min=0), default=None,
              help="The posture shown first [default: the robot file's working posture].")
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None, callback=_out_folder,
              help="Output folder [default: build/<name>/view].")
def view(robot, pose, posture, out_dir):
    """Write <name>.html: the machine in 3D (base, limbs, platform, wrist and tool), each joint's
    value and travel beside it, fields and sliders for the pose, the limbs coloured by their
    warnings. One self-contained file: three.js and the routine compiled to WebAssembly are inside
    it (without a WebAssembly toolchain, the machine is drawn at the pose kingen computed and the
    page says what the sliders need). A joint typed in the page's table moves the machine there
    (the routine's forward kinematics). The address #pose=x,y,z,roll,pitch,yaw&posture=K (or
    #joints=q1,...,qn, mm and radians) sets the pose on load; the page writes what its routine
    computed into the element #kingen-joints."""
    from ..hosts.wasm.build import wasm_toolchain
    from ..runtime.files import default_out_dir, write_atomic
    from ..view import page_html, scene

    model = load_model(robot)
    if posture is not None and posture >= model.postures:
        raise click.BadParameter(f"{model.name} has postures 0 to {model.postures - 1}", param_hint="--posture")
    out_dir = Path(out_dir or default_out_dir(model) / "view")
    page = page_html(model, scene(model, pose, posture), title=f"{model.name}: kingen view")
    target = out_dir / f"{model.name}.html"
    write_atomic(target, page)
    say(f"wrote {target} ({len(page.encode()) / 1e6:.2f} MB)")
    toolchain = wasm_toolchain()
    if not toolchain.ready:
        say(f"the page draws the machine at the pose kingen computed; its sliders need the routine compiled to "
            f"WebAssembly: {toolchain.problem}")
    return 0
