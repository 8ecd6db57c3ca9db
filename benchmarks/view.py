"""kingen view's answer to a slider change, measured in the page itself, printed as a Markdown
table, and with --json written as plain data for benchmarks/run.py (the performance page's
section). Figures are printed, never asserted.

    python benchmarks/view.py [--robots hexapod,tau,...] [--changes N] [--json FILE]

Per robot: `kingen view ROBOT`, then the page opened in headless Chromium (WebGL by SwiftShader,
on the processor) with ``#bench=N``: the page moves its first free coordinate's slider N times,
each an input event as a drag makes, and times with performance.now() each answer (the
WebAssembly routine's call, the drawing's update and three.js's render) and the routine's call
alone, into #kingen-timing (milliseconds: median, 95th percentile, worst of the changes; the first
answer, at load, apart: it compiles the shaders). Chromium is driven through its DevTools protocol
(a WebSocket client of a few lines below), because the timings need real time, not the virtual
time of --dump-dom. Goal: a change answered within 50 ms. Also the page's size (goal
under 5 MB).
"""

import argparse
import base64
import json
import os
import re
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from c_host import _table

ABOUT = ("[kingen view](how-to/view.md)'s page: its size and how long it takes to answer a slider change "
         "(the WebAssembly routine, the drawing's update and its render), measured in the page with "
         "performance.now() in headless Chromium drawing with SwiftShader on the processor. Goals: under 5 MB, "
         "a change answered within 50 ms.")
"""What the section measures, for the performance page (links relative to docs/)."""
ROBOTS = ("hexapod", "tau", "ceart", "exechon_wrist", "tricept_wrist3")
CHROMIUM = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader", "--no-first-run", "--disable-background-networking",
            "--window-size=1200,800", "--remote-debugging-port=0"]
WAIT_S = 120
"""How long the page may take (real time, the timings need it) to write all its answers' timing."""


class DevTools:
    """The smallest client of Chromium's DevTools protocol over a WebSocket (RFC 6455: masked text
    frames out, unfragmented frames in): ``evaluate(expression)`` in the page."""

    def __init__(self, url):
        host, port, path = re.match(r"ws://([^:/]+):(\d+)(/.*)", url).groups()
        self.socket = socket.create_connection((host, int(port)))
        key = base64.b64encode(os.urandom(16)).decode()
        self.socket.sendall((f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                             f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        answer = b""
        while b"\r\n\r\n" not in answer:
            answer += self.socket.recv(1)
        self.number = 0

    def _read(self, count):
        data = b""
        while len(data) < count:
            data += self.socket.recv(count - len(data))
        return data

    def evaluate(self, expression):
        self.number += 1
        message = json.dumps({"id": self.number, "method": "Runtime.evaluate",
                              "params": {"expression": expression, "returnByValue": True}}).encode()
        size = len(message)
        header = struct.pack("!BB", 0x81, 0x80 | size) if size < 126 else struct.pack("!BBH", 0x81, 0x80 | 126, size)
        mask = os.urandom(4)
        self.socket.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(message)))
        while True:
            first, second = self._read(2)
            size = second & 0x7F
            if size == 126:
                size = struct.unpack("!H", self._read(2))[0]
            elif size == 127:
                size = struct.unpack("!Q", self._read(8))[0]
            reply = json.loads(self._read(size)) if first & 0x0F == 1 else {}
            if reply.get("id") == self.number:
                return reply["result"]["result"].get("value")


def measure(robot, changes, folder):
    """{robot, bytes, changes, median_ms, p95_ms, max_ms, routine_median_ms, routine_max_ms} of one page."""
    done = subprocess.run([sys.executable, "-m", "kingen.cli", "view", robot, "-o", str(folder)], capture_output=True,
                          text=True)
    if done.returncode != 0:
        raise SystemExit(f"kingen view {robot} failed: {done.stderr.strip()}")
    page = Path(folder) / f"{robot}.html"
    log = Path(folder) / "chromium.log"
    with log.open("w") as stream:
        browser = subprocess.Popen([*CHROMIUM, f"--user-data-dir={Path(folder) / 'profile'}",
                                    f"{page.as_uri()}#bench={changes}"], stderr=stream)
    try:
        started, port = time.monotonic(), None
        while port is None and time.monotonic() - started < WAIT_S:
            time.sleep(0.2)
            port = re.search(r"DevTools listening on ws://[^:]+:(\d+)/", log.read_text())
        port = port.group(1)
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list"))
        tools = DevTools(next(target["webSocketDebuggerUrl"] for target in targets if target["type"] == "page"))
        started, timing = time.monotonic(), None
        while time.monotonic() - started < WAIT_S:
            text = tools.evaluate("(document.getElementById('kingen-timing') || {}).textContent || ''")
            if text and json.loads(text)["changes"] >= changes:
                timing = json.loads(text)
                break
            time.sleep(0.5)
    finally:
        browser.kill()
        browser.wait()
    if timing is None:
        raise SystemExit(f"{robot}: the page did not answer {changes} changes within {WAIT_S} s")
    return {"robot": robot, "bytes": page.stat().st_size, **timing}


def markdown(figures):
    """The figures as one Markdown table."""
    rows = [["robot", "page (MB)", "first answer, at load (ms)", "changes", "median ms", "95% ms", "worst ms",
             "over 50 ms", "routine median ms", "routine worst ms"]]
    rows += [[row["robot"], f"{row['bytes'] / 1e6:.2f}", f"{row['load_ms']:.1f}", str(row["changes"]), f"{row['median_ms']:.1f}",
              f"{row['p95_ms']:.1f}", f"{row['max_ms']:.1f}", str(row["over_50_ms"]), f"{row['routine_median_ms']:.2f}",
              f"{row['routine_max_ms']:.2f}"] for row in figures["pages"]]
    return (f"Each page's first free coordinate moved {figures['changes']} times by input events; every answer timed "
            "in the page (performance.now(), 0.1 ms resolution); the first answer, at load, compiles the shaders. "
            f"The machine's load average over a minute, at the end: {figures['load_average']:.1f} (its other work "
            "makes the worst changes).\n\n" + _table(rows[0], rows[1:]))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--changes", type=int, default=300)
    parser.add_argument("--json", type=Path, default=None)
    arguments = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:  # the machine's load average: the other work the pages shared it with
        pages = [measure(robot, arguments.changes, Path(scratch) / robot) for robot in arguments.robots.split(",")]
    figures = {"changes": arguments.changes, "pages": pages, "load_average": os.getloadavg()[0]}
    print(markdown(figures))
    if arguments.json is not None:
        arguments.json.write_text(json.dumps(figures, indent=2) + "\n")


if __name__ == "__main__":
    main()
