"""The view's self-contained HTML page, and the same view for another page to embed.

``page_html(robot, scene, title=...)`` is one HTML document that needs no network: three.js
(``vendor/three.module.min.js``, THREE_VERSION, MIT licence, ``vendor/three.LICENSE``) inside it as
text imported from a Blob URL, the scene (kingen.view.scene) as JSON, the page's script
(``view.js``), and, where the WebAssembly toolchain is installed, the robot's generated C library
compiled to WebAssembly (kingen.hosts.wasm) in base64 with its JavaScript glue, which answers every
change of the pose. Without the toolchain the page draws the machine at the poses kingen computed
(the scene's, and its frames') and says what the sliders need.

``view_fragment(robot, scene, title=...)`` embeds that page in another HTML page as an
``<iframe srcdoc>`` (its scripts and element ids kept apart from the host page's): a report puts
the returned text where the view goes.
"""

import base64
import html
import json
import string
from pathlib import Path

from ..defaults import VERSION

HERE = Path(__file__).resolve().parent
THREE_VERSION = "0.160.0"
"""The three.js release vendored in ``vendor/`` (npm package ``three``, MIT licence)."""


def _json_in_script(data):
    """JSON that cannot end the <script> element it stands in (every '<' written as \\u003c)."""
    return json.dumps(data, allow_nan=False, separators=(",", ":")).replace("<", "\\u003c")


def _routine_script(robot):
    """(script, note): the <script> elements that set ``window.kingenRoutine`` (the robot's C
    library compiled to WebAssembly, base64, started by the wasm host's JS glue) and None; ("",
    what the sliders need) where the WebAssembly toolchain is not installed."""
    from ..hosts.wasm.build import GLUE, compile_wasm, module_meta, wasm_toolchain

    toolchain = wasm_toolchain()
    if not toolchain.ready:
        return "", (f"The machine is drawn at the pose kingen computed. The sliders need the routine compiled to "
                    f"WebAssembly, which this page was written without: {toolchain.problem}. Install it and run "
                    f"kingen view again.")
    module = base64.b64encode(compile_wasm(robot).read_bytes()).decode()
    start = (f"window.kingenRoutineReady = KingenWasm.instantiate(Uint8Array.from(atob({json.dumps(module)}), "
             f"c => c.charCodeAt(0)), {_json_in_script(module_meta(robot))}).then(routine => {{ "
             f"window.kingenRoutine = routine; }});")
    return f"<script>\n{GLUE.read_text()}\n</script>\n<script>\n{start}\n</script>", None


def page_html(robot, scene, *, title, routine=True):
    """The whole self-contained page (module docstring) of ``scene`` (kingen.view.scene.scene of
    ``robot``, with any overlays), titled ``title``; ``routine`` False leaves the WebAssembly
    routine out (the page then draws the scene's poses only)."""
    script, note = _routine_script(robot) if routine else ("", "The machine is drawn at the poses kingen computed.")
    scene = dict(scene, no_routine=note) if note else scene
    page = string.Template((HERE / "page.html").read_text())
    return page.substitute(
        banner=f"kingen {VERSION} view of {html.escape(robot.name)} (three.js {THREE_VERSION}, MIT licence)",
        title=html.escape(title), description=html.escape(scene.get("description", "")),
        about=f"Drawn with three.js {THREE_VERSION} (MIT licence), inside this page.",
        travel_from=html.escape(scene.get("travel_from", "the robot file")),
        scene=_json_in_script(scene), three=(HERE / "vendor" / "three.module.min.js").read_text(),
        routine=script, view=(HERE / "view.js").read_text())


def view_fragment(robot, scene, *, title, routine=True, height=640):
    """The view of :func:`page_html` as an ``<iframe srcdoc>`` ``height`` px high, for another
    HTML page to hold (module docstring). The attribute is single-quoted, only ``&``, ``'`` and
    ``<`` escaped in it: the scene's JSON, all double quotes, keeps its size, and no tag of the
    page stands in the report's text."""
    page = page_html(robot, scene, title=title, routine=routine)
    inside = page.replace("&", "&amp;").replace("'", "&#39;").replace("<", "&lt;")
    return (f'<iframe class="kingen-view-frame" title="{html.escape(title)}" style="width:100%;height:{int(height)}px;'
            f"border:1px solid #ddd\" srcdoc='{inside}'></iframe>")
