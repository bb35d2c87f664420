"""The web demo, started as ``motionbits-demo`` would be, driven in a real browser.

Debian's ``chromium`` is driven by PyPI ``playwright`` (``executable_path`` points at the
system browser; no browser is ever downloaded). Without chromium or playwright the test
skips and says why. Set ``MOTIONBITS_DEMO_SCREENSHOT=PATH`` to keep the screenshot.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.parse
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

pytest.importorskip("gradio")
pytest.importorskip("av")
pytest.importorskip("pycocotools")

from demos.media import write_demo_clip  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
# the installed console script when this environment has it (CI: pip install -e), else the
# same entry point through python -m
_SCRIPT = Path(sys.executable).with_name("motionbits-demo")
DEMO = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "demos.app"]
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def demo_server(tmp_path_factory):
    """``motionbits-demo`` on a free port; yields (url, seconds to the first HTTP 200)."""
    port = _free_port()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
               GRADIO_ANALYTICS_ENABLED="False")
    log = open(tmp_path_factory.mktemp("demo") / "server.log", "w+")
    t0 = time.perf_counter()
    proc = subprocess.Popen([*DEMO, "--host", "127.0.0.1", "--port", str(port), "--nodes", "900"],
                            cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}/"
    try:
        while True:
            try:
                with urllib.request.urlopen(url, timeout=2) as r:
                    if r.status == 200:
                        break
            except OSError:
                pass
            if proc.poll() is not None or time.perf_counter() - t0 > 90:
                log.seek(0)
                pytest.fail(f"motionbits-demo did not answer on {url}:\n{log.read()[-2000:]}")
            time.sleep(0.25)
        yield url, time.perf_counter() - t0
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def test_demo_answers_http_within_30_s(demo_server):
    _, seconds = demo_server
    print(f"motionbits-demo answered HTTP after {seconds:.1f} s")
    assert seconds < 30


def uploaded(page, name: str) -> None:
    """Wait until the upload of ``name`` has finished (its download link is shown)."""
    page.locator(f'#video-in [data-testid="download-link"][download="{name}"]').wait_for()


def _fetch_image(url: str) -> np.ndarray:
    with urllib.request.urlopen(url, timeout=10) as r:
        return np.asarray(Image.open(io.BytesIO(r.read())).convert("RGB"))


@pytest.mark.skipif(CHROMIUM is None, reason="no chromium on PATH (Debian: apt-get install chromium)")
def test_demo_in_browser(demo_server, tmp_path):
    playwright = pytest.importorskip("playwright.sync_api", reason="PyPI playwright not installed")
    url, _ = demo_server
    clip = write_demo_clip(tmp_path / "clip.mp4", n_frames=12, size=(240, 320))
    not_video = tmp_path / "notes.txt"
    not_video.write_text("this is not a video")

    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 1100})
            page.set_default_timeout(45_000)
            page.goto(url)
            upload = page.locator("#video-in input[type=file]")

            # bad input: a readable message in the page, no stack trace
            upload.set_input_files(str(not_video))
            uploaded(page, "notes.txt")
            page.click("#run")
            status = page.locator("#status")
            status.get_by_text("not a video").wait_for()
            assert "Traceback" not in page.content()

            # a real clip: upload, run, overlay, table
            page.locator("#video-in button[aria-label='Clear']").first.click()
            upload.set_input_files(str(clip))
            uploaded(page, "clip.mp4")
            page.click("#run")
            status.get_by_text("MotionBits in the last frame").wait_for(timeout=90_000)
            page.locator("#overlay video").wait_for()
            assert page.locator("#overlay video").get_attribute("src")
            # the browser decodes the overlay (H.264): it knows the frame size and raised no error
            page.wait_for_function("() => { const v = document.querySelector('#overlay video');"
                                   " return v && v.readyState >= 1 && v.videoWidth > 0; }")
            assert page.eval_on_selector("#overlay video", "v => [v.videoWidth, v.videoHeight, v.error]") \
                == [320, 240, None]
            rows = int(page.locator("#table [role=grid]").get_attribute("aria-rowcount")) - 1  # - header
            assert rows >= 3

            summary_link = page.locator("#summary a").first.get_attribute("href")
            summary = json.loads(urllib.request.urlopen(urllib.parse.urljoin(url, summary_link)).read())
            largest = summary["motionbits"][0]

            # question -> the stub cites the largest MotionBit -> highlighted on the last frame
            page.fill("#question textarea", "Which body is the largest?")
            page.click("#ask")
            page.locator("#cited").get_by_text("Highlighted").wait_for()
            answer = page.locator("#answer textarea").input_value()
            assert f"[{largest['mark']}]" in answer
            assert f"(id {largest['id']})" in page.locator("#cited").inner_text()
            src = page.locator("#highlight img").first.get_attribute("src")
            shot = _fetch_image(urllib.parse.urljoin(url, src))
            assert shot.shape[:2] == tuple(summary["size"])
            x0, y0, x1, y1 = largest["box"]
            inside = shot[y0:y1, x0:x1].mean()
            outside = np.concatenate([shot[:y0].reshape(-1, 3), shot[y1:].reshape(-1, 3)]).mean()
            assert inside > 1.5 * outside, (inside, outside)  # the rest of the frame is dimmed

            # show the overlay's last frame (the first has no MotionBit yet) in the screenshot
            page.eval_on_selector("#overlay video", "v => { v.currentTime = v.duration; }")
            page.wait_for_timeout(500)
            page.screenshot(path=str(tmp_path / "demo.png"), full_page=True)
        finally:
            browser.close()
    keep = os.environ.get("MOTIONBITS_DEMO_SCREENSHOT")
    if keep:
        shutil.copy(tmp_path / "demo.png", keep)
