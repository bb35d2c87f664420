"""overlay.mp4 plays in a real browser (headless Chromium), where OpenCV's mp4v does not.

Needs Debian's `chromium` and PyPI's `playwright` (never `playwright install`); skipped
without them.
"""

import shutil

import cv2
import numpy as np
import pytest

from motionbits.video_writer import write_h264

playwright = pytest.importorskip("playwright.sync_api")
CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium executable")


def _state(page, html, name):
    html.write_text(f'<video id="v" src="{name}" muted preload="auto"></video>')
    page.goto(html.as_uri())
    page.wait_for_function("() => { const v = document.getElementById('v'); return v.readyState >= 2 || v.error; }",
                           timeout=10000)
    return page.evaluate("() => { const v = document.getElementById('v'); return "
                         "{error: v.error && v.error.code, width: v.videoWidth, height: v.videoHeight, frames: "
                         "Math.round(v.duration * 10)}; }")


def test_h264_overlay_plays_in_chromium_and_mp4v_does_not(tmp_path):
    frames = [np.full((48, 64, 3), 25 * t, np.uint8) for t in range(6)]
    write_h264(frames, tmp_path / "h264.mp4", fps=10)
    old = cv2.VideoWriter(str(tmp_path / "mp4v.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 10.0, (64, 48))
    for f in frames:
        old.write(f)
    old.release()
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            page = browser.new_page()
            assert _state(page, tmp_path / "page.html", "h264.mp4") == {"error": None, "width": 64, "height": 48,
                                                                        "frames": 6}
            assert _state(page, tmp_path / "page.html", "mp4v.mp4")["error"] == 4  # MEDIA_ERR_SRC_NOT_SUPPORTED
        finally:
            browser.close()
