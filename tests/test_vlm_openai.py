"""OpenAICompatibleVLM against a local chat-completions server started by the test."""
from __future__ import annotations

import base64
import contextlib
import io
import json
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np
import pytest
from PIL import Image

from vlm_adapters import OpenAICompatibleVLM


class _Server:
    """A minimal /v1/chat/completions endpoint that validates requests and records them."""

    def __init__(self):
        self.requests: list[dict] = []
        self.headers: list[dict] = []
        server = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):  # keep test output quiet
                pass

            def do_POST(self):
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                server.requests.append(body)
                server.headers.append(dict(self.headers))
                if self.path != "/v1/chat/completions":
                    return self._send(404, {"error": {"message": f"no route {self.path}"}})
                user = body["messages"][-1]
                images = [p for p in user["content"] if p["type"] == "image_url"]
                texts = [p["text"] for p in user["content"] if p["type"] == "text"]
                if not images or not texts:
                    return self._send(400, {"error": {"message": "need images and a prompt"}})
                sizes = []
                for p in images:
                    header, data = p["image_url"]["url"].split(",", 1)
                    assert header.startswith("data:image/") and header.endswith(";base64")
                    sizes.append(Image.open(io.BytesIO(base64.b64decode(data))).size)
                answer = f"saw {len(images)} images of {sizes[0][0]}x{sizes[0][1]}; asked: {texts[-1]}"
                self._send(200, {
                    "id": "x", "object": "chat.completion", "model": body["model"],
                    "choices": [{"index": 0, "message": {"role": "assistant", "content": answer},
                                 "finish_reason": "stop"}],
                })

            def _send(self, code, payload):
                data = json.dumps(payload).encode()
                self.send_response(code)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture()
def server():
    s = _Server()
    yield s
    s.close()


def _frames(n=3, h=48, w=64):
    rng = np.random.default_rng(0)
    return [rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for _ in range(n)]


def test_request_carries_images_prompt_and_settings(server):
    vlm = OpenAICompatibleVLM(server.url, model="Qwen/Qwen2.5-VL-7B-Instruct", api_key="secret")
    frames = _frames()
    answer = vlm.generate(frames, "What moved?", system="Be brief.", max_new_tokens=32, seed=7)
    assert answer == "saw 3 images of 64x48; asked: What moved?"
    req = server.requests[-1]
    assert req["model"] == "Qwen/Qwen2.5-VL-7B-Instruct"
    assert req["messages"][0] == {"role": "system", "content": "Be brief."}
    assert req["max_tokens"] == 32 and req["temperature"] == 0.0 and req["seed"] == 7
    assert server.headers[-1]["Authorization"] == "Bearer secret"
    # the PNG data URLs decode to the very pixels that were sent
    url = req["messages"][1]["content"][0]["image_url"]["url"]
    decoded = np.asarray(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))))
    np.testing.assert_array_equal(decoded, frames[0])


def test_pil_frames_jpeg_and_downscale(server):
    vlm = OpenAICompatibleVLM(server.url, model="m", image_format="jpeg", max_image_side=32)
    frames = [Image.fromarray(f) for f in _frames(2)]
    assert vlm.generate(frames, "Q", do_sample=True, temperature=0.5) == "saw 2 images of 32x24; asked: Q"
    assert server.requests[-1]["temperature"] == 0.5
    assert server.requests[-1]["messages"][0]["content"][0]["image_url"]["url"].startswith("data:image/jpeg;base64,")


def test_generate_batch_keeps_order(server):
    vlm = OpenAICompatibleVLM(server.url, model="m", max_workers=3)
    videos = [_frames(n) for n in (1, 2, 3, 4)]
    answers = vlm.generate_batch(videos, [f"q{i}" for i in range(4)])
    assert answers == [f"saw {n} images of 64x48; asked: q{i}" for i, n in enumerate((1, 2, 3, 4))]


def test_http_error_is_reported_with_body(server):
    vlm = OpenAICompatibleVLM(server.url + "/wrong", model="m")
    with pytest.raises(RuntimeError, match="HTTP 404.*no route"):
        vlm.generate(_frames(1), "Q")


def test_unreachable_server_is_a_connection_error():
    import socket

    with socket.socket() as s:  # a port with nothing listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    vlm = OpenAICompatibleVLM(f"http://127.0.0.1:{port}/v1", model="m", timeout=5)
    with pytest.raises(ConnectionError, match="is the server running"):
        vlm.generate(_frames(1), "Q")


class _Quiet(BaseHTTPRequestHandler):
    """A request handler that logs nothing; :meth:`answer` reads the request and starts a
    200 response (headers follow)."""

    def log_message(self, *args):
        pass

    def answer(self):
        self.rfile.read(int(self.headers["Content-Length"]))
        self.send_response(200)


@contextlib.contextmanager
def _serve(handler):
    """A local HTTP server with ``handler`` in a thread; yields its ``/v1`` URL."""
    httpd = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}/v1"
    finally:
        httpd.shutdown()
        httpd.server_close()


@pytest.fixture()
def canned():
    """A server answering every request with the raw bytes ``canned.reply`` (a short body
    for ``canned.length`` > its size: the connection ends mid-body)."""

    class Handler(_Quiet):
        def do_POST(self):
            self.answer()
            self.send_header("Content-Length", str(Handler.length or len(Handler.reply)))
            self.end_headers()
            self.wfile.write(Handler.reply)

    Handler.reply, Handler.length = b"", None
    with _serve(Handler) as Handler.url:
        yield Handler


def _reply(content) -> bytes:
    return json.dumps({"choices": [{"message": {"content": content}}]}).encode()


@pytest.mark.parametrize("reply, length, words", [
    (b"", None, "did not answer JSON"),
    (b"<html>Bad gateway</html>", None, "did not answer JSON"),
    (b"\xff\xfe not utf-8", None, "did not answer JSON"),
    (b'{"choi', 100, "broken HTTP response"),
    (_reply(123), None, "content is not text"),
    (_reply(0), None, "content is not text"),
    (_reply({"text": "hi"}), None, "content is not text"),
    (_reply([{"type": "text", "text": None}]), None, "content is not text"),
])
def test_garbage_replies_are_runtime_errors(canned, reply, length, words):
    canned.reply, canned.length = reply, length
    with pytest.raises(RuntimeError, match=words):
        OpenAICompatibleVLM(canned.url, model="m", timeout=5).generate(_frames(1), "Q")


def test_content_parts_and_null_content(canned):
    vlm = OpenAICompatibleVLM(canned.url, model="m", timeout=5)
    canned.reply = _reply([{"type": "text", "text": "the cup "}, "[1]", {"type": "image_url"}])
    assert vlm.generate(_frames(1), "Q") == "the cup [1]"
    canned.reply = _reply(None)
    assert vlm.generate(_frames(1), "Q") == ""


@pytest.fixture()
def slow():
    """A server that sends its headers, then waits 3 s before the body."""
    import time

    class Handler(_Quiet):
        def do_POST(self):
            self.answer()
            self.send_header("Content-Length", "200")
            self.end_headers()
            self.wfile.flush()
            time.sleep(3)

    with _serve(Handler) as url:
        yield url


def test_a_slow_answer_is_a_timeout_naming_the_server(slow):
    # was: a bare TimeoutError("timed out") from the socket, naming nothing
    with pytest.raises(TimeoutError, match=r"did not answer within 0\.5 s") as info:
        OpenAICompatibleVLM(slow, model="m", timeout=0.5).generate(_frames(1), "Q")
    assert "127.0.0.1" in str(info.value)


def test_a_connection_reset_while_reading_names_the_server(monkeypatch):
    # was: a bare ConnectionResetError "[Errno 104] Connection reset by peer"
    class Reset:
        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def read(self):
            raise ConnectionResetError(104, "Connection reset by peer")

    monkeypatch.setattr("urllib.request.urlopen", lambda req, timeout=None: Reset())
    with pytest.raises(ConnectionError, match="connection to http://h:1/v1/chat/completions failed"):
        OpenAICompatibleVLM("http://h:1/v1", model="m").generate(_frames(1), "Q")


@pytest.mark.parametrize("reply, words", [
    (b"[" * 100_000 + b"]" * 100_000, "did not answer JSON"),  # was: RecursionError
    (json.dumps({"error": {"message": "model 'm' not found", "code": 404}}).encode(),
     "answered an error: model 'm' not found"),
])
def test_deep_or_error_replies_are_runtime_errors(canned, reply, words):
    canned.reply = reply
    with pytest.raises(RuntimeError, match=words):
        OpenAICompatibleVLM(canned.url, model="m", timeout=5).generate(_frames(1), "Q")


@pytest.mark.parametrize("kwargs, words", [
    (dict(base_url=None), "base_url must be a str"),  # was: AttributeError
    (dict(image_format="tif"), "image_format"),  # was: KeyError 'TIF' from PIL at the first request
    (dict(max_image_side=0), "max_image_side"),  # was: every frame sent as a 1x1 image
    (dict(timeout=0), "timeout"),  # was: a non-blocking socket, failing at once
    (dict(timeout=-1), "timeout"),  # was: ValueError from the socket at the first request
])
def test_bad_settings_fail_at_construction(kwargs, words):
    kwargs = {"base_url": "http://localhost:8000/v1", **kwargs}
    with pytest.raises(ValueError, match=words):
        OpenAICompatibleVLM(model="m", **kwargs)
