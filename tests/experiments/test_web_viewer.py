"""The web viewer shows a recording: a run recorded, served by Rerun on 127.0.0.1, opened in
Debian's headless chromium (software rendering) and photographed through the DevTools protocol;
the picture must hold the robots' colour where the arena is drawn."""

from __future__ import annotations

import asyncio
import base64
import io
import json
import shutil
import subprocess
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

import dream

rerun = pytest.importorskip("rerun", reason="Rerun recordings need rerun-sdk (the rerun extra, Python >= 3.11)")
from PIL import Image  # noqa: E402
from tornado.websocket import websocket_connect  # noqa: E402  (tornado comes with distributed)

from dream.recording import STATUS_COLOURS, _free_port, _viewer, _wait_listening  # noqa: E402

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
#: Where the default layout draws the arena in a 1280x800 window (left of the measures).
ARENA_VIEW = (slice(60, 490), slice(200, 780))


def robot_pixels(png: bytes) -> int:
    """How many pixels of the arena's view have the colour of a robot without faults."""
    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)[ARENA_VIEW]
    return int((np.abs(image - np.array(STATUS_COLOURS[0])).max(axis=2) <= 30).sum())


async def screenshot(socket_url: str) -> bytes:
    connection = await websocket_connect(socket_url, max_message_size=1 << 28)
    try:
        connection.write_message(json.dumps({"id": 1, "method": "Page.captureScreenshot", "params": {"format": "png"}}))
        while True:
            answer = json.loads(await connection.read_message())
            if answer.get("id") == 1:
                return base64.b64decode(answer["result"]["data"])
    finally:
        connection.close()


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium), so no browser test")
def test_web_viewer_shows_the_robots(tmp_path: Path):
    recording = tmp_path / "run.rrd"
    dream.run("hrvo-circle", n=20, backend="fast", steps=30, rerun=recording)
    grpc, web, debug = _free_port(0), _free_port(0), _free_port(0)
    serve = [_viewer(), "--serve-web", "--bind", "127.0.0.1", "--port", str(grpc), "--web-viewer-port", str(web)]
    server = subprocess.Popen([*serve, str(recording)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    browser = None
    try:
        _wait_listening(web, server)
        page = f"http://127.0.0.1:{web}/?url=rerun%2Bhttp://127.0.0.1:{grpc}/proxy"
        browser = subprocess.Popen(
            [
                CHROMIUM, "--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
                "--window-size=1280,800", f"--remote-debugging-port={debug}", f"--user-data-dir={tmp_path / 'profile'}",
                page,
            ],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        _wait_listening(debug, browser)
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{debug}/json", timeout=30))
        socket_url = next(t["webSocketDebuggerUrl"] for t in targets if t["type"] == "page")
        shots = []
        deadline = time.monotonic() + 120  # the viewer's WebAssembly compiles, then draws in software
        while time.monotonic() < deadline:
            shots.append(robot_pixels(asyncio.run(screenshot(socket_url))))
            if shots[-1] > 100:
                break
            time.sleep(2)
        assert shots[-1] > 100, f"no robots drawn after 120 s (robot pixels in each screenshot: {shots})"
    finally:
        for process in (browser, server):
            if process is not None:
                process.terminate()
                process.wait(timeout=30)
