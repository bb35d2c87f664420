"""Every bad or edge input gets a one-line error or a correct result (issue 12).

One table of cases over the CLI (``segment``, ``batch``, ``bench``, ``eval``, ``synth``,
``benchmark``, ``compare``, ``scenes``) and the Python API of ``motionbits``,
``somprompt`` and ``vlm_adapters``. Each case is run and given a verdict:

- ``clear error``: CLI exit status 2 (130 for an interrupt) with exactly one stderr line
  ``motionbits CMD: error: ...`` holding the expected words; API: a ValueError /
  TypeError / OSError / ImportError whose message is one line holding them;
- ``correct result``: exit status 0 / a return value that passes the case's check;
- ``traceback``: an exception of another kind, or a traceback on stderr;
- ``silently wrong``: success where an error was due, or a result that fails its check;
- ``hang``: no answer within the case's time limit;
- ``unclear error``: a failure without traceback whose message is not one line naming the
  problem (e.g. behind a stale progress bar, or about something the user never passed).

Every case must get the verdict it expects, and leave nothing partial (``*.partial-*``)
or stale on disk. ``python tests/test_bad_inputs.py`` prints the verdict counts.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import signal
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable
from unittest import mock

import cv2
import numpy as np
import pytest
from PIL import Image

CLEAR, CORRECT, TRACEBACK, WRONG, HANG, UNCLEAR = (
    "clear error", "correct result", "traceback", "silently wrong", "hang", "unclear error")
VERDICTS = (CLEAR, CORRECT, TRACEBACK, WRONG, HANG, UNCLEAR)
API_ERRORS = (ValueError, TypeError, OSError, ImportError)
SEG = ["--nodes", "400", "--max-side", "160", "--quiet"]  # small and fast
SEG_BIG = ["--nodes", "2500", "--max-side", "320", "--quiet"]  # finds the demo clip's bodies


class Hang(BaseException):
    """Raised by the alarm when a case runs past its time limit."""


@dataclass
class Outcome:
    rc: int | None = None  # CLI exit status (None for an API call)
    out: str = ""
    err: str = ""
    exc: BaseException | None = None  # exception that escaped
    value: Any = None  # API return value
    warns: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Case:
    id: str
    run: Callable[[Path], Outcome]
    expect: str  # CLEAR or CORRECT
    words: str = ""  # CLEAR: words the message must hold
    check: Callable[[Outcome, Path], bool] | None = None  # CORRECT: the result is right
    absent: tuple[str, ...] = ()  # paths under tmp that must not exist afterwards
    rc: int = 2
    limit: float = 60.0
    requires: Callable[[], str | None] | None = None  # returns why the case cannot run here


# --------------------------------------------------------------------------- inputs

def _clip(n=6, size=(120, 160)):
    from motionbits.synth import demo_clip

    return demo_clip(n_frames=n, size=size)


def _write_frames(folder: Path, frames, ext=".png", convert=None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for i, f in enumerate(frames):
        img = Image.fromarray(f) if convert is None else convert(f)
        img.save(folder / f"{i:05d}{ext}")
    return folder


def _write_video(path: Path, frames, fourcc="mp4v", fps=10) -> Path:
    h, w = frames[0].shape[:2]
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    for f in frames:
        wr.write(cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    wr.release()
    return path


def _header_frames(avi: bytes, n: int) -> bytes:
    """An AVI whose headers (avih dwTotalFrames, strh dwLength) say ``n`` frames."""
    import struct

    b = bytearray(avi)
    i, j = b.find(b"avih") + 8 + 16, b.find(b"strh") + 8 + 32
    b[i:i + 4] = b[j:j + 4] = struct.pack("<I", n)
    return bytes(b)


def build_assets(root: Path) -> Path:
    """Every input file the cases read (a few hundred kB), under ``root``."""
    root.mkdir(parents=True, exist_ok=True)
    clip = _clip()
    frames = clip.frames
    _write_frames(root / "frames", frames)
    _write_video(root / "clip.mp4", frames)
    avi = _write_video(root / "clip.avi", _clip(20).frames, "MJPG").read_bytes()
    (root / "cut.avi").write_bytes(avi[: len(avi) // 2])  # header says 20 frames
    (root / "short_header.avi").write_bytes(_header_frames(avi, 10))  # 20 frames, header says 10
    (root / "empty.mp4").write_bytes(b"")
    (root / "text.mp4").write_text("not a video\n" * 50)
    (root / "empty_dir").mkdir()
    (root / "txt_dir").mkdir()
    (root / "txt_dir" / "a.txt").write_text("hello")
    # 16-bit greyscale and 16-bit RGB (OpenCV writes 16-bit RGB PNGs; PIL only reads them),
    # at 240x320 where the segmenter finds the demo's bodies, and their 8-bit twins
    big = _clip(4, (240, 320)).frames
    _write_frames(root / "rgb8", big)
    grey = [cv2.cvtColor(f, cv2.COLOR_RGB2GRAY) for f in big]
    _write_frames(root / "grey8", grey)
    _write_frames(root / "grey16", grey, convert=lambda g: Image.fromarray(g.astype(np.uint16) * 257))
    (root / "rgb16").mkdir()
    for i, f in enumerate(big):
        cv2.imwrite(str(root / "rgb16" / f"{i:05d}.png"),
                    cv2.cvtColor(f, cv2.COLOR_RGB2BGR).astype(np.uint16) * 257)
    # the 240x320 frames as one multi-page TIFF, and the small clip as an animated GIF
    pages = [Image.fromarray(f) for f in big]
    pages[0].save(root / "pages.tiff", save_all=True, append_images=pages[1:])
    gif = [Image.fromarray(f) for f in frames]
    gif[0].save(root / "anim.gif", save_all=True, append_images=gif[1:])  # GIF87a: no frame durations
    _write_frames(root / "rgba", frames, convert=lambda f: Image.fromarray(f).convert("RGBA"))
    _write_frames(root / "palette", frames, convert=lambda f: Image.fromarray(f).quantize(64))
    _write_frames(root / "float_big", frames[:3], ".tif",
                  convert=lambda f: Image.fromarray(f[..., 0].astype(np.float32)))
    nan = frames[0][..., 0].astype(np.float32) / 255
    nan[5, 5] = np.nan
    _write_frames(root / "float_nan", [nan] * 3, ".tif", convert=Image.fromarray)
    mixed = _write_frames(root / "mixed", frames[:3])
    Image.fromarray(_clip(1, (100, 160)).frames[0]).save(mixed / "00003.png")
    corrupt = _write_frames(root / "corrupt", frames[:4])
    (corrupt / "00002.png").write_bytes(b"\x89PNG\r\n\x1a\n broken")
    _write_frames(root / "thin", [np.full((8, 4000, 3), 90 + 20 * i, np.uint8) for i in range(2)])
    _write_frames(root / "tiny", [np.zeros((8, 8, 3), np.uint8)] * 2)
    _write_frames(root / "one", frames[:1])
    unpadded = root / "unpadded"  # FFmpeg's %d.png: 0.png .. 11.png
    unpadded.mkdir()
    for i, f in enumerate(_clip(12).frames):
        Image.fromarray(f).save(unpadded / f"{i}.png")
    (root / "png.mp4").write_bytes((root / "one" / "00000.png").read_bytes())  # a PNG named .mp4
    # frames copied from a Mac: AppleDouble "._*.png" files and a folder named like an image
    hidden = _write_frames(root / "hidden", frames[:3])
    (hidden / "._00001.png").write_bytes(b"\x00\x05\x16\x07\x00\x02\x00\x00Mac OS X")
    (hidden / ".thumb.png").write_bytes(b"")
    (hidden / "zz.png").mkdir()
    _write_frames(root / "ünï cødé", frames[:3])
    # a MoRiBo dataset: track/scene/{frames/, gt.png}
    scene = root / "data" / "robot" / "scene_0000"
    _write_frames(scene / "frames", frames)
    Image.fromarray(clip.gt.astype(np.uint16)).save(scene / "gt.png")
    # ... whose gt.png is not the frames' size, or whose frames differ in size
    bad = root / "data_bad_gt" / "robot" / "scene_0000"
    _write_frames(bad / "frames", frames[:3])
    Image.fromarray(clip.gt[:60].astype(np.uint16)).save(bad / "gt.png")
    bad = root / "data_mixed_frames" / "robot" / "scene_0000"
    _write_frames(bad / "frames", frames[:3])
    Image.fromarray(_clip(1, (100, 160)).frames[0]).save(bad / "frames" / "00001.png")
    Image.fromarray(clip.gt.astype(np.uint16)).save(bad / "gt.png")
    one = root / "data_one_frame" / "robot" / "scene_0000"
    _write_frames(one / "frames", frames[:1])
    Image.fromarray(clip.gt.astype(np.uint16)).save(one / "gt.png")
    pred = root / "pred" / "robot"
    pred.mkdir(parents=True)
    Image.fromarray(clip.gt.astype(np.uint16)).save(pred / "scene_0000.png")
    small = root / "pred_small" / "robot"
    small.mkdir(parents=True)
    Image.fromarray(clip.gt[:60].astype(np.uint16)).save(small / "scene_0000.png")
    return root


@pytest.fixture(scope="module")
def assets(tmp_path_factory) -> Path:
    return build_assets(tmp_path_factory.mktemp("assets"))


# --------------------------------------------------------------------------- runners

def cli(*argv: str, patches: tuple = ()) -> Callable[[Path], Outcome]:
    """A CLI case: ``motionbits ARGV`` in-process ("{a}" = assets, "{t}" = tmp)."""
    def run(tmp: Path) -> Outcome:
        from motionbits.cli import main

        args = [a.format(a=tmp.parent / "assets", t=tmp) for a in argv]
        out, err = io.StringIO(), io.StringIO()
        o = Outcome()
        with contextlib.ExitStack() as stack:
            for p in patches:
                stack.enter_context(p())
            stack.enter_context(contextlib.redirect_stdout(out))
            stack.enter_context(contextlib.redirect_stderr(err))
            try:
                o.rc = main(args)
            except SystemExit as exc:  # argparse
                o.rc = exc.code if isinstance(exc.code, int) else 2
            except Hang:
                raise
            except BaseException as exc:  # noqa: BLE001 - a traceback is a verdict here
                o.exc = exc
        o.out, o.err = out.getvalue(), err.getvalue()
        return o
    return run


def api(fn: Callable[[Path], Any]) -> Callable[[Path], Outcome]:
    """An API case: ``fn(tmp)``; its return value is checked, its exception judged."""
    def run(tmp: Path) -> Outcome:
        o = Outcome()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                o.value = fn(tmp)
            except Hang:
                raise
            except BaseException as exc:  # noqa: BLE001
                o.exc = exc
        o.warns = [str(w.message) for w in caught]
        return o
    return run


def verdict(case: Case, o: Outcome) -> tuple[str, str]:
    """(verdict, why) of one outcome."""
    if o.rc is None:  # API
        if o.exc is not None:
            msg = str(o.exc)
            if not isinstance(o.exc, API_ERRORS) or "\n" in msg.strip() or not msg:
                return TRACEBACK, f"{type(o.exc).__name__}: {msg[:300]}"
            if case.expect == CLEAR and case.words.lower() in msg.lower():
                return CLEAR, msg
            return UNCLEAR, f"{type(o.exc).__name__}: {msg[:300]}"
        if case.expect == CORRECT and (case.check is None or case.check(o, None)):
            return CORRECT, ""
        return WRONG, f"returned {str(o.value)[:200]!r}"
    if o.exc is not None or "Traceback" in o.err:
        return TRACEBACK, f"{type(o.exc).__name__}: {o.exc}" if o.exc else o.err[-300:]
    lines = [ln for ln in o.err.splitlines() if ln.strip()]
    if o.rc != 0:
        one = len(lines) == 1 and lines[0].startswith("motionbits") and "error" in lines[0]
        if (case.expect == CLEAR and one and o.rc == case.rc
                and case.words.lower() in lines[0].lower()):
            return CLEAR, lines[0]
        return UNCLEAR, f"rc {o.rc}: {o.err[-300:]!r}"
    if case.expect == CORRECT and (case.check is None or case.check(o, None)):
        return CORRECT, ""
    return WRONG, f"rc 0: {o.out[-200:]!r} {o.err[-200:]!r}"


def run_case(case: Case, tmp: Path) -> tuple[str, str, Outcome | None]:
    def alarm(*_):
        raise Hang()

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, case.limit)
    try:
        o = case.run(tmp)
    except Hang:
        return HANG, f"no answer in {case.limit:g} s", None
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    if case.check is not None and o.exc is None:
        ok = case.check
        case = Case(case.id, case.run, case.expect, case.words, lambda o_, _: ok(o_, tmp),
                    case.absent, case.rc, case.limit, case.requires)
    return (*verdict(case, o), o)


# --------------------------------------------------------------------------- checks

def labels_in(out: Path) -> list[str]:
    return sorted(p.name for p in (out / "labels").glob("*.png"))


def seg_ok(n: int, out: str = "out") -> Callable[[Outcome, Path], bool]:
    """segment wrote n label maps, an overlay and a summary, and said so."""
    def check(o: Outcome, tmp: Path) -> bool:
        d = tmp / out
        summary = json.loads((d / "summary.json").read_text())
        return (len(labels_in(d)) == n == summary["frames"]
                and (d / "overlay.mp4").stat().st_size > 0 and "wrote" in o.out)
    return check


def same_labels_as(reference: str) -> Callable[[Outcome, Path], bool]:
    """The run's labels equal those of the 8-bit frames in assets/``reference`` (so the
    16-bit frames were scaled, not clipped), and something was found."""
    def check(o: Outcome, tmp: Path) -> bool:
        from motionbits.cli import main

        with contextlib.redirect_stdout(io.StringIO()):
            main(["segment", str(tmp.parent / "assets" / reference), "--out", str(tmp / "ref"), *SEG_BIG])
        a, b = ([cv2.imread(str(p), cv2.IMREAD_UNCHANGED) for p in sorted((tmp / d / "labels").glob("*.png"))]
                for d in ("out", "ref"))
        return len(a) == len(b) == 4 and all(np.array_equal(x, y) for x, y in zip(a, b)) and a[-1].max() > 0
    return check


def prepared(setup: Callable[[Path], None], runner: Callable[[Path], Outcome]):
    """Run ``setup(tmp)`` (e.g. an earlier output) before the case itself."""
    def run(tmp: Path) -> Outcome:
        setup(tmp)
        return runner(tmp)
    return run


def in_tmp(runner: Callable[[Path], Outcome]):
    """Run the case with ``tmp`` as the current folder."""
    def run(tmp: Path) -> Outcome:
        with _chdir(tmp):
            return runner(tmp)
    return run


@contextlib.contextmanager
def _chdir(path: Path):  # contextlib.chdir of Python >= 3.11
    import os

    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def earlier_output(tmp: Path) -> None:
    from motionbits.cli import main

    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["segment", str(tmp.parent / "assets" / "frames"), "--out", str(tmp / "out"), *SEG]) == 0


def unrelated_files(tmp: Path) -> None:
    (tmp / "out").mkdir(parents=True)
    (tmp / "out" / "thesis.tex").write_text("precious")


def robot_track_with_thesis(tmp: Path) -> None:
    unrelated_files(tmp / "d" / "robot")  # d/robot/out/thesis.tex


def a_file(name: str) -> Callable[[Path], None]:
    return lambda tmp: (tmp / name).write_text("a file")


def fail_nth(target: str, n: int, exc: BaseException | None = None, result: Any = None):
    """A patch: ``target`` works n times, then raises ``exc`` (or returns ``result``)."""
    def factory():
        import importlib

        parts = target.split(".")
        for i in range(len(parts) - 1, 0, -1):  # the longest importable prefix is the module
            try:
                owner = importlib.import_module(".".join(parts[:i]))
                break
            except ImportError:
                continue
        for name in parts[i:-1]:
            owner = getattr(owner, name)
        attr = parts[-1]
        orig = getattr(owner, attr)
        calls = {"n": 0}

        def wrapper(*a, **k):
            calls["n"] += 1
            if calls["n"] > n:
                if exc is not None:
                    raise exc
                return result
            return orig(*a, **k)
        return mock.patch.object(owner, attr, wrapper)
    return factory


def without(module: str):
    """A patch: ``import module`` fails as if the package were not installed."""
    return lambda: mock.patch.dict(sys.modules, {module: None})


def no_torch_ops():
    return mock.patch.dict(sys.modules, {"torch": None, "motionbits.torch_ops": None})


def mujoco_renders() -> str | None:
    try:
        from motionbits.synth.mujoco_backend import render_check
    except ImportError as exc:
        return str(exc)
    return render_check()


def rerun_as_prediction(tmp: Path) -> None:
    """A 6-frame segment output replaced by a 1-frame one (whose labels are all background)
    at the place where ``eval`` looks for the prediction of scene_0000."""
    from motionbits.cli import main

    out = str(tmp / "pred" / "robot" / "scene_0000")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["segment", str(tmp.parent / "assets" / "frames"), "--out", out, *SEG]) == 0
        assert main(["segment", str(tmp.parent / "assets" / "one"), "--out", out, "--overwrite", *SEG]) == 0


def a_json(name: str, data: Any) -> Callable[[Path], None]:
    return lambda tmp: (tmp / name).write_text(json.dumps(data))


def a_sequence(mixed: bool = False) -> Callable[[Path], None]:
    """A DAVIS-style sequence tmp/seq (frames/, gt/) of the 6 asset frames, one box mask
    each; ``mixed``: its frame 00001.png shrunk to 100x80."""
    def setup(tmp: Path) -> None:
        seq = tmp / "seq"
        (seq / "frames").mkdir(parents=True)
        (seq / "gt").mkdir()
        mask = np.zeros((120, 160), np.uint8)
        mask[20:60, 30:80] = 255
        for f in sorted((tmp.parent / "assets" / "frames").glob("*.png")):
            img = Image.open(f)
            (img.resize((100, 80)) if mixed and f.name == "00001.png" else img).save(seq / "frames" / f.name)
            Image.fromarray(mask).save(seq / "gt" / f.name)
    return setup


def _copy(tmp: Path, asset: str, name: str) -> Path:
    """assets/``asset`` copied to tmp/``name``."""
    (tmp / name).write_bytes((tmp.parent / "assets" / asset).read_bytes())
    return tmp / name


def _pred_in_tmp(tmp: Path) -> None:
    """The perfect predictions of assets/pred in tmp itself (tmp/robot/scene_0000.png)."""
    import shutil

    shutil.copytree(tmp.parent / "assets" / "pred" / "robot", tmp / "robot")


def eval_json_f1(value: float) -> Callable[[Outcome, Path], bool]:
    def check(o: Outcome, tmp: Path) -> bool:
        scores = json.loads((tmp / "s.json").read_text())
        return math.isclose(scores["macro"]["F1"], value)
    return check


# --------------------------------------------------------------------------- API helpers

def _segment(frames, config=None, flow=None):
    from motionbits import MotionBitsSegmenter

    seg = MotionBitsSegmenter(config, flow=flow)
    return [seg.update(f) for f in frames]


def _work_size(shape, config):
    """(labels shape, working size) after one frame of ``shape``."""
    from motionbits import MotionBitsSegmenter

    seg = MotionBitsSegmenter(config)
    res = seg.update(np.zeros((*shape, 3), np.uint8))
    return res.labels.shape, seg._work_size


def _small_config(**kw):
    from motionbits import MotionBitsConfig

    return MotionBitsConfig(n_nodes=400, max_side=160, **kw)


def _flow_returning(fn):
    def flow(prev, nxt):
        return fn(prev)
    return flow


def _many_ids(n: int, shape=(300, 300), seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lab = np.zeros(shape, np.int64)
    lab.ravel()[:n] = rng.permutation(n) + 1
    return lab


def _eval_many(n: int, shape):
    from motionbits.eval import evaluate_frame

    gt = _many_ids(n, shape)
    perm = np.r_[0, np.random.default_rng(1).permutation(n) + 1]
    return evaluate_frame(perm[gt], gt)  # the same objects, other ids: all matched, F1 = 1


def _config(**kw):
    from motionbits import MotionBitsConfig

    return MotionBitsConfig(**kw)


def _adapter_frame(frame):
    from vlm_adapters.base import to_rgb_frames

    return to_rgb_frames([frame])[0]


def _stub_generate(frames):
    from vlm_adapters.stub import StubVLM

    return StubVLM(["ok"]).generate(frames, "what moved?")


def _phrases(text, **kw):
    from vlm_adapters.phrases import phrases_from_answer

    return phrases_from_answer(text, **kw)


def _openai_generate(prompt="what moved?", **kw):
    """OpenAICompatibleVLM.generate with a canned reply in place of the network; returns
    the request body it would have sent."""
    from vlm_adapters import OpenAICompatibleVLM

    vlm, sent = OpenAICompatibleVLM("http://127.0.0.1:9/v1", model="m"), []
    with mock.patch.object(vlm, "_post", lambda body: sent.append(body) or {"choices": [{"message": {"content": "ok"}}]}):
        vlm.generate([np.zeros((8, 8, 3), np.uint8)], prompt, **kw)
    return sent[-1]


def _data_url_pixels(url: str) -> np.ndarray:
    import base64

    return np.asarray(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))))


def _parse(text, labels=None, **kw):
    from somprompt import parse_answer

    return parse_answer(text, labels=labels, **kw)


def _draw(labels, shape=None, scene=None, **kw):
    from somprompt import SetOfMarkRenderer

    shape = shape or labels.shape
    scene = np.zeros((*shape, 3), np.uint8) if scene is None else scene
    return SetOfMarkRenderer(**kw).render(scene, labels)


_GRAD16 = (np.arange(64 * 64, dtype=np.uint32).reshape(64, 64) * 16).astype(np.uint16)
_F = _clip(3).frames  # three 120x160 frames for API cases
_LAB = np.zeros((20, 20), np.int64)
_LAB[2:8, 2:8] = 3
_LAB[10:18, 10:18] = 5


def _seg():
    """A demos Segmentation of two frames (no segmenter run): ids 3 and 5 in the last."""
    from demos.segmentation import Segmentation

    return Segmentation("clip.mp4", [0, 1], [np.zeros((20, 20, 3), np.uint8)] * 2, [_LAB, _LAB])


def _h264_failed_over(tmp, frames):
    """write_h264 ``frames`` over an earlier file: it must fail and leave that file as it was."""
    from motionbits.video_writer import write_h264

    old = tmp / "v.mp4"
    old.write_bytes(b"an earlier video")
    try:
        write_h264(frames, old)
    except ValueError:
        return old.read_bytes(), sorted(p.name for p in tmp.iterdir())
    return None


_BATCH_OPT = {"nodes": 400, "max_side": 160}


def _run_batch(tmp, items, out="o", options=_BATCH_OPT, **kw):
    """run_batch over ``items`` (paths under assets, or BatchInputs) on one worker."""
    from motionbits.batch import BatchInput, run_batch

    items = [it if not isinstance(it, str) else BatchInput(str(tmp.parent / "assets" / it), Path(it).stem)
             for it in items]
    return run_batch(items, out if out == "" else str(tmp / out), options, workers=kw.pop("workers", 1),
                     quiet=True, **kw)


def _zip(tmp, maps, indices):
    from demos.media import write_labels_zip

    return write_labels_zip(maps, indices, tmp / "labels.zip")


_M2 = np.zeros((2, 6, 6), bool)  # two overlapping instance masks
_M2[0, :3], _M2[1, 2:] = True, True


def _masks_to_labels(*a, **kw):
    from vlm_adapters.grounding import masks_to_label_map

    return masks_to_label_map(_M2, *a, **kw)


def _yoloe(**kw):
    """A YOLOEDetector around a placeholder model (no ultralytics, no torch)."""
    from vlm_adapters.grounding import YOLOEDetector

    return YOLOEDetector(object(), device="cpu", **kw)


def _yoloe_sent(phrases):
    """The phrase lists a YOLOEDetector's detect hands on to the model (``_activate``)."""
    det, sent = _yoloe(), []

    class Sent(Exception):
        pass

    def activate(p):
        sent.append(list(p))
        raise Sent

    det._activate = activate
    with contextlib.suppress(Sent):
        det.detect(np.zeros((8, 8, 3), np.uint8), phrases)
    return sent


def _marks_json(marks=None, **kw):
    """``somprompt.marks_to_json`` of the marks of ``_LAB`` (or of ``marks``)."""
    import somprompt

    if marks is None:
        marks = somprompt.describe_marks(somprompt.LabelRegions(_LAB), somprompt.MarkRegistry())
    return somprompt.marks_to_json(marks, **kw)


def _vlm_yoloe(**kw):
    """vlm-yoloe with string options whose files do not exist (the option checks come first)."""
    from vlm_adapters.plugin import vlm_yoloe_method

    return vlm_yoloe_method(**{"vlm": "stub:- a cup: moved", "yoloe": "/nonexistent/yoloe-11l-seg.pt",
                               "text_encoder": "/nonexistent/mobileclip_blt.ts", **kw})


class _NoDetector:
    def detect(self, image, phrases):
        from vlm_adapters.grounding import Detections

        return Detections.empty(*np.shape(image)[:2])


def _method(**kw):
    from vlm_adapters import StubVLM, TextGrounder, VLMYOLOEMethod

    return VLMYOLOEMethod(kw.pop("vlm", StubVLM("- a cup: moved")), TextGrounder(_NoDetector()), **kw)


def _fake_transformers(**kw):
    """A TransformersVLM over a processor that would take anything (no torch)."""
    from types import SimpleNamespace

    from vlm_adapters.hf import TransformersVLM

    return TransformersVLM(object(), SimpleNamespace(chat_template="{{ messages }}"), frames_as="images", **kw)


# --------------------------------------------------------------------------- the table

S = "segment"
CASES: list[Case] = [
    # ---- segment: inputs
    Case("segment/nonexistent", cli(S, "{t}/no/such.mp4", "--out", "{t}/out"), CLEAR, "not found", absent=("out",)),
    Case("segment/empty-file", cli(S, "{a}/empty.mp4", "--out", "{t}/out"), CLEAR, "empty.mp4", absent=("out",)),
    Case("segment/text-as-mp4", cli(S, "{a}/text.mp4", "--out", "{t}/out"), CLEAR, "could not open", absent=("out",)),
    Case("segment/dev-zero", cli(S, "/dev/zero", "--out", "{t}/out"), CLEAR, "/dev/zero", absent=("out",)),
    Case("segment/empty-path", prepared(lambda t: _write_frames(t, _F[:2]), in_tmp(cli(S, "", "--out", "{t}/out"))), CLEAR,
         "input path is empty", absent=("out",)),  # was: segmented the current folder ("" = ".")
    Case("segment/empty-folder", cli(S, "{a}/empty_dir", "--out", "{t}/out"), CLEAR, "contains no images", absent=("out",)),
    Case("segment/folder-of-txt", cli(S, "{a}/txt_dir", "--out", "{t}/out"), CLEAR, "contains no images", absent=("out",)),
    Case("segment/mixed-sizes", cli(S, "{a}/mixed", "--out", "{t}/out", *SEG), CLEAR,
         "started at 160x120: the frames of one video must all have one size", absent=("out",)),
    Case("segment/corrupt-png-among-good", cli(S, "{a}/corrupt", "--out", "{t}/out", *SEG), CLEAR, "00002.png", absent=("out",)),
    Case("segment/broken-link-frame", prepared(lambda t: (_write_frames(t / "f", _F[:2]), (t / "f" / "00002.png").symlink_to(
        t / "gone.png")), cli(S, "{t}/f", "--out", "{t}/out", *SEG)), CLEAR, "00002.png in",
        absent=("out",)),  # was: skipped silently, later frames shifted
    Case("segment/truncated-video-warns", cli(S, "{a}/cut.avi", "--out", "{t}/out", *SEG), CORRECT,
         check=lambda o, t: ("header says 20 frames" in o.err and json.loads(
             (t / "out/summary.json").read_text())["input_frames"] == {"expected": 20, "decoded": 10})),
    Case("segment/truncated-video-strict", cli(S, "{a}/cut.avi", "--out", "{t}/out", "--strict", *SEG), CLEAR,
         "only 10 could be decoded", absent=("out",)),
    Case("segment/16bit-grey-pngs", cli(S, "{a}/grey16", "--out", "{t}/out", *SEG_BIG), CORRECT, check=same_labels_as("grey8")),
    Case("segment/16bit-rgb-pngs", cli(S, "{a}/rgb16", "--out", "{t}/out", *SEG_BIG), CORRECT, check=same_labels_as("rgb8")),
    Case("segment/float-tiff-out-of-range", cli(S, "{a}/float_big", "--out", "{t}/out", *SEG), CLEAR, "outside [0, 1]", absent=("out",)),
    Case("segment/float-tiff-nan", cli(S, "{a}/float_nan", "--out", "{t}/out", *SEG), CLEAR, "NaN", absent=("out",)),
    Case("segment/8x4000-frame", cli(S, "{a}/thin", "--out", "{t}/out", *SEG), CLEAR, "at least 20 px", absent=("out",)),
    Case("segment/8x8-frame", cli(S, "{a}/tiny", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(2)),  # upsampled
    Case("segment/rgba-pngs", cli(S, "{a}/rgba", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(6)),
    Case("segment/palette-pngs", cli(S, "{a}/palette", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(6)),
    Case("segment/grey-pngs", cli(S, "{a}/grey8", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(4)),
    Case("segment/hidden-files-skipped", cli(S, "{a}/hidden", "--out", "{t}/out", *SEG), CORRECT,
         check=seg_ok(3)),  # was: "could not read image ._00001.png"
    Case("segment/multi-page-tiff", cli(S, "{a}/pages.tiff", "--out", "{t}/out", *SEG_BIG), CORRECT,
         check=same_labels_as("rgb8")),  # was: the first page only, 1 frame, no warning
    Case("segment/animated-gif", cli(S, "{a}/anim.gif", "--out", "{t}/out", *SEG), CORRECT,
         check=seg_ok(6)),  # was: 1 frame and "the header says 6 frames ... truncated or corrupt file"
    Case("segment/header-says-fewer-frames", cli(S, "{a}/short_header.avi", "--out", "{t}/out", *SEG), CORRECT,
         check=seg_ok(20)),  # was: 10 frames, the other 10 dropped silently
    Case("segment/start-past-header-count", cli(S, "{a}/short_header.avi", "--out", "{t}/out", "--start", "15",
                                                "--frames", "2", *SEG), CORRECT,
         check=lambda o, t: labels_in(t / "out") == ["00015.png", "00016.png"]),  # was: "past the last frame (10 frames)"
    Case("segment/png-named-mp4", cli(S, "{a}/png.mp4", "--out", "{t}/out", *SEG), CORRECT,
         check=seg_ok(1)),  # was: "--start 0 is past the last frame (-9223372036854775808 frames)"
    Case("api/unpadded-frame-names-in-order", api(lambda t: [int(f.mean() * 1000) for f in __import__(
        "motionbits.video").video.iter_frames(t.parent / "assets" / "unpadded")]), CORRECT,
         check=lambda o, t: o.value == [int(f.mean() * 1000) for f in _clip(12).frames]),  # was: 0, 1, 10, 11, 2, ...
    Case("segment/one-frame", cli(S, "{a}/one", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(1)),
    Case("segment/single-image-file", cli(S, "{a}/frames/00000.png", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(1)),
    Case("segment/unicode-paths", cli(S, "{a}/ünï cødé", "--out", "{t}/ôut put", *SEG), CORRECT, check=seg_ok(3, "ôut put")),
    Case("segment/folder", cli(S, "{a}/frames", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(6)),
    Case("segment/video", cli(S, "{a}/clip.mp4", "--out", "{t}/out", *SEG), CORRECT, check=seg_ok(6)),
    Case("segment/window", cli(S, "{a}/frames", "--out", "{t}/out", "--start", "1", "--every", "2", "--frames", "2", *SEG),
         CORRECT, check=lambda o, t: labels_in(t / "out") == ["00001.png", "00003.png"]),
    Case("segment/frames-beyond-end", cli(S, "{a}/frames", "--out", "{t}/out", "--frames", "50", *SEG), CORRECT, check=seg_ok(6)),
    Case("segment/nested-new-out", cli(S, "{a}/one", "--out", "{t}/a/b/c", *SEG), CORRECT, check=seg_ok(1, "a/b/c")),
    Case("segment/out-empty", in_tmp(cli(S, "{a}/one", "--out", "", *SEG)), CLEAR,
         "--out is empty"),  # was: "--out . already holds files", or errno 16 in an empty folder
    Case("segment/out-current-folder", in_tmp(cli(S, "{a}/one", "--out", ".", *SEG)), CLEAR,
         "is the current folder"),  # was: "[Errno 16] Device or resource busy: '.' -> '..partial-...old'"
    Case("segment/out-current-folder-by-path", in_tmp(cli(S, "{a}/one", "--out", "{t}", *SEG)), CLEAR,
         "is the current folder"),  # was: replaced the (empty) current folder with the output
    # ---- segment: options (checked before any frame)
    Case("segment/every-0", cli(S, "{a}/frames", "--out", "{t}/out", "--every", "0"), CLEAR, "--every", absent=("out",)),
    Case("segment/every-negative", cli(S, "{a}/frames", "--out", "{t}/out", "--every", "-2"), CLEAR, "--every", absent=("out",)),
    Case("segment/frames-0", cli(S, "{a}/frames", "--out", "{t}/out", "--frames", "0"), CLEAR, "--frames", absent=("out",)),
    Case("segment/start-negative", cli(S, "{a}/frames", "--out", "{t}/out", "--start", "-1"), CLEAR, "--start", absent=("out",)),
    Case("segment/start-past-end", cli(S, "{a}/frames", "--out", "{t}/out", "--start", "6"), CLEAR, "past the last frame", absent=("out",)),
    Case("segment/start-past-end-video", cli(S, "{a}/clip.mp4", "--out", "{t}/out", "--start", "99"), CLEAR, "past the last frame", absent=("out",)),
    Case("segment/nodes-0", cli(S, "{a}/frames", "--out", "{t}/out", "--nodes", "0"), CLEAR, "--nodes", absent=("out",)),
    Case("segment/nodes-huge", cli(S, "{a}/frames", "--out", "{t}/out", "--nodes", "999999999"), CLEAR, "--nodes", absent=("out",)),
    Case("segment/nodes-text", cli(S, "{a}/frames", "--out", "{t}/out", "--nodes", "many"), CLEAR, "--nodes", absent=("out",)),
    Case("segment/max-side-0", cli(S, "{a}/frames", "--out", "{t}/out", "--max-side", "0"), CLEAR, "--max-side", absent=("out",)),
    Case("segment/max-side-huge", cli(S, "{a}/frames", "--out", "{t}/out", "--max-side", "100000"), CLEAR, "--max-side", absent=("out",)),
    Case("segment/fps-0", cli(S, "{a}/frames", "--out", "{t}/out", "--fps", "0"), CLEAR, "--fps", absent=("out",)),
    Case("segment/fps-negative", cli(S, "{a}/frames", "--out", "{t}/out", "--fps", "-5"), CLEAR, "--fps", absent=("out",)),
    Case("segment/fps-nan", cli(S, "{a}/frames", "--out", "{t}/out", "--fps", "nan"), CLEAR, "--fps", absent=("out",)),
    Case("segment/fps-inf", cli(S, "{a}/frames", "--out", "{t}/out", "--fps", "inf"), CLEAR, "--fps", absent=("out",)),
    Case("segment/fps-huge", cli(S, "{a}/frames", "--out", "{t}/out", "--fps", "1e300"), CLEAR, "--fps must be at most",
         absent=("out",)),  # was: OverflowError traceback from PyAV
    Case("segment/fps-tiny", cli(S, "{a}/frames", "--out", "{t}/out", "--fps", "1e-6"), CLEAR,
         "--fps must be at least 0.001", absent=("out",)),  # was: the overlay written at 24 fps
    Case("segment/backend-unknown", cli(S, "{a}/frames", "--out", "{t}/out", "--backend", "cuda"), CLEAR, "backend", absent=("out",)),
    Case("segment/backend-torch-without-torch", cli(S, "{a}/frames", "--out", "{t}/out", "--backend", "torch",
                                                    patches=(no_torch_ops,)), CLEAR, "torch", absent=("out",)),
    Case("segment/config-is-a-folder", cli(S, "{a}/one", "--out", "{t}/out", "--config", "{a}/frames"), CLEAR,
         "is a folder", absent=("out",)),  # was: "config file ... does not exist"
    Case("segment/config-binary-json", prepared(lambda t: (t / "c.json").write_bytes(b"\x00\xdb\xff" * 20), cli(
        S, "{a}/one", "--out", "{t}/out", "--config", "{t}/c.json")), CLEAR, "c.json is not a text file",
        absent=("out",)),  # was: "'utf-8' codec can't decode byte 0xdb ..." (no file named)
    Case("segment/config-video", cli(S, "{a}/one", "--out", "{t}/out", "--config", "{a}/clip.mp4"), CLEAR,
         "must end in .toml or .json", absent=("out",)),  # was: the UTF-8 error, before the suffix check
    Case("segment/config-empty-path", cli(S, "{a}/one", "--out", "{t}/out", "--config", "", *SEG), CLEAR,
         "config path is empty", absent=("out",)),  # was: ignored, the defaults used
    Case("segment/config-json-key-twice", prepared(lambda t: (t / "c.json").write_text(
        '{"n_nodes": 400, "n_nodes": 900}'), cli(S, "{a}/one", "--out", "{t}/out", "--config", "{t}/c.json")),
         CLEAR, "'n_nodes' is given twice", absent=("out",)),  # was: the last one (900) used
    Case("segment/config-json-nested-deep", prepared(lambda t: (t / "c.json").write_text("[" * 100_000 + "]" * 100_000),
         cli(S, "{a}/one", "--out", "{t}/out", "--config", "{t}/c.json")), CLEAR, "nested too deeply",
         absent=("out",)),  # was: RecursionError traceback
    Case("segment/config-json-5000-digits", prepared(lambda t: (t / "c.json").write_text('{"n_nodes": ' + "9" * 5000 + "}"),
         cli(S, "{a}/one", "--out", "{t}/out", "--config", "{t}/c.json")), CLEAR, "c.json is not valid JSON",
         absent=("out",)),  # was: "Exceeds the limit (4300 digits) ..." (no file named)
    Case("api/config-file-bom", api(lambda t: ((t / "c.toml").write_bytes(b"\xef\xbb\xbfn_nodes = 400\n"),
                                              __import__("motionbits.config_file").config_file.load_config(t / "c.toml"))[1]),
         CORRECT, check=lambda o, t: o.value.n_nodes == 400),  # was: "not valid TOML: Invalid statement (line 1, column 1)"
    Case("api/config-file-path-none", api(lambda t: __import__("motionbits.config_file").config_file.load_config(None)),
         CLEAR, "config path must be"),  # was: "expected str, bytes or os.PathLike object, not NoneType"
    Case("api/config-from-dict-none", api(lambda t: __import__("motionbits.config_file").config_file.config_from_dict(None)),
         CLEAR, "values must be a mapping"),  # was: "'NoneType' object is not iterable"
    Case("segment/unknown-option", cli(S, "{a}/frames", "--out", "{t}/out", "--nodez", "3"), CLEAR, "unrecognized", absent=("out",)),
    # ---- segment: outputs
    Case("segment/out-is-a-file", prepared(a_file("out"), cli(S, "{a}/frames", "--out", "{t}/out")), CLEAR, "is a file"),
    Case("segment/out-under-a-file", prepared(a_file("f"), cli(S, "{a}/frames", "--out", "{t}/f/out")), CLEAR, "cannot write"),
    Case("segment/out-not-writable", cli(S, "{a}/frames", "--out", "{t}/out", *SEG, patches=(
        fail_nth("tempfile.mkdtemp", 0, PermissionError(13, "Permission denied")),)), CLEAR, "permission denied", absent=("out",)),
    Case("segment/labels-not-writable", cli(S, "{a}/frames", "--out", "{t}/out", *SEG, patches=(
        fail_nth("cv2.imwrite", 2, result=False),)), CLEAR, "could not write", absent=("out",)),
    Case("segment/disk-full", cli(S, "{a}/frames", "--out", "{t}/out", *SEG, patches=(
        fail_nth("cv2.imwrite", 3, OSError(28, "No space left on device")),)), CLEAR, "no space left", absent=("out",)),
    Case("segment/out-of-memory", cli(S, "{a}/frames", "--out", "{t}/out", *SEG, patches=(
        fail_nth("motionbits.segmenter.MotionBitsSegmenter.update", 2, MemoryError()),)), CLEAR, "out of memory", absent=("out",)),
    Case("segment/interrupted", cli(S, "{a}/frames", "--out", "{t}/out", *SEG, patches=(
        fail_nth("motionbits.segmenter.MotionBitsSegmenter.update", 2, KeyboardInterrupt()),)), CLEAR, "interrupted",
        absent=("out",), rc=130),
    Case("segment/rerun-refused", prepared(earlier_output, cli(S, "{a}/one", "--out", "{t}/out", *SEG)), CLEAR,
         "--overwrite"),
    Case("segment/rerun-overwrite-fewer-frames", prepared(earlier_output, cli(S, "{a}/one", "--out", "{t}/out", "--overwrite", *SEG)),
         CORRECT, check=seg_ok(1)),
    Case("segment/overwrite-unrelated-folder", prepared(unrelated_files, cli(S, "{a}/one", "--out", "{t}/out", "--overwrite", *SEG)),
         CLEAR, "did not write"),
    Case("segment/failed-rerun-keeps-old", prepared(earlier_output, cli(S, "{a}/corrupt", "--out", "{t}/out", "--overwrite", *SEG)),
         CLEAR, "00002.png"),
    # ---- bench
    Case("bench/size-too-small", cli("bench", "--size", "16x12"), CLEAR, "--size 16x12 is too small"),
    Case("bench/size-malformed", cli("bench", "--size", "640"), CLEAR, "WIDTHxHEIGHT"),
    Case("bench/frames-1", cli("bench", "--frames", "1"), CLEAR, "--frames"),
    Case("bench/scaling-frames-1", cli("bench", "--scaling-frames", "1"), CLEAR, "--scaling-frames"),
    Case("bench/nodes-5", cli("bench", "--nodes", "5"), CLEAR, "--nodes"),
    Case("bench/max-scenes-0", cli("bench", "--max-scenes", "0"), CLEAR, "--max-scenes"),
    Case("bench/data-missing", cli("bench", "--data", "{t}/nope"), CLEAR, "not found"),
    Case("bench/backend-torch-without-torch", cli("bench", "--backend", "torch", patches=(no_torch_ops,)), CLEAR, "torch"),
    Case("bench/small-run", cli("bench", "--frames", "3", "--size", "64x48", "--nodes", "100", "--no-exact", "--no-scaling"),
         CORRECT, check=lambda o, t: "per frame" in o.out and "3 frames 48x64" in o.out),
    # ---- eval
    Case("eval/pred-missing", cli("eval", "--pred", "{t}/nope", "--gt", "{a}/data"), CLEAR, "not found"),
    Case("eval/gt-missing", cli("eval", "--pred", "{a}/pred", "--gt", "{t}/nope"), CLEAR, "nope"),
    Case("eval/size-mismatch", cli("eval", "--pred", "{a}/pred_small", "--gt", "{a}/data", "--quiet"), CLEAR, "shape"),
    Case("eval/json-is-a-folder", prepared(lambda t: (t / "j").mkdir(), cli(
        "eval", "--pred", "{a}/pred", "--gt", "{a}/data", "--json", "{t}/j")), CLEAR, "is a folder"),
    Case("eval/json-empty", cli("eval", "--pred", "{a}/pred", "--gt", "{a}/data", "--quiet", "--json", ""), CLEAR,
         "--json is empty"),  # was: scored, no JSON written, exit 0
    Case("eval/pred-empty", prepared(_pred_in_tmp, in_tmp(cli(
        "eval", "--pred", "", "--gt", "{a}/data", "--quiet"))), CLEAR,
         "--pred is empty"),  # was: the current folder scored as the prediction
    Case("eval/pred-name-dir-empty", prepared(_pred_in_tmp, in_tmp(cli(
        "eval", "--pred", "x=", "--gt", "{a}/data", "--quiet"))), CLEAR,
         "DIR of NAME=DIR is empty"),  # was: the current folder scored as the prediction
    Case("eval/pred-name-empty", cli("eval", "--pred", "={a}/pred", "--gt", "{a}/data", "--quiet"), CLEAR,
         "NAME of NAME=DIR is empty"),  # was: scored in a row with no name, exit 0
    Case("eval/gt-empty", cli("eval", "--pred", "{a}/pred", "--gt", "", "--quiet"), CLEAR,
         "--gt is empty"),  # was: the current folder searched for scenes
    Case("eval/duplicate-names", cli("eval", "--pred", "x={a}/pred", "--pred", "x={a}/pred", "--gt", "{a}/data", "--quiet"),
         CLEAR, "share the name"),
    Case("eval/no-prediction-for-scene", prepared(lambda t: (t / "p").mkdir(), cli(
        "eval", "--pred", "{t}/p", "--gt", "{a}/data", "--quiet")), CLEAR, "scene_0000"),
    Case("eval/perfect", cli("eval", "--pred", "{a}/pred", "--gt", "{a}/data", "--quiet", "--json", "{t}/s.json"),
         CORRECT, check=eval_json_f1(1.0)),
    Case("eval/segment-output-latest-run", prepared(rerun_as_prediction, cli(
        "eval", "--pred", "{t}/pred", "--gt", "{a}/data", "--quiet", "--json", "{t}/s.json")),
        CORRECT, check=eval_json_f1(0.0)),
    # ---- synth
    Case("synth/out-is-a-file", prepared(a_file("s"), cli("synth", "--track", "robot", "--out", "{t}/s")), CLEAR, "is a file"),
    Case("synth/out-empty", in_tmp(cli("synth", "--track", "robot", "--out", "")), CLEAR,
         "--out is empty"),  # was: wrote ./robot and said "wrote /robot"
    Case("synth/without-mujoco", cli("synth", "--track", "robot", "--out", "{t}/s", patches=(without("mujoco"),)),
         CLEAR, "pip install", absent=("s",)),
    Case("synth/size-too-small", cli("synth", "--track", "robot", "--out", "{t}/s", "--size", "16x16"), CLEAR, "too small", absent=("s",)),
    Case("synth/scenes-0", cli("synth", "--track", "robot", "--out", "{t}/s", "--scenes", "0"), CLEAR, "--scenes", absent=("s",)),
    Case("synth/scenes-huge", cli("synth", "--track", "robot", "--out", "{t}/s", "--scenes", "10" * 10, "--quiet"),
         CLEAR, "--scenes must be at most 10000", absent=("s",)),  # was: OverflowError traceback (tqdm's len)
    Case("synth/frames-1", cli("synth", "--track", "robot", "--out", "{t}/s", "--frames", "1"), CLEAR, "--frames", absent=("s",)),
    Case("synth/seed-negative", cli("synth", "--track", "robot", "--out", "{t}/s", "--seed", "-1", "--scenes", "1",
                                    "--frames", "2", "--size", "64x48", "--quiet"), CLEAR, "--seed", absent=("s",)),
    Case("synth/track-unknown", cli("synth", "--track", "car", "--out", "{t}/s"), CLEAR, "--track", absent=("s",)),
    Case("synth/track-not-empty", prepared(robot_track_with_thesis, cli(
        "synth", "--track", "robot", "--out", "{t}/d")), CLEAR, "--overwrite",
        requires=mujoco_renders),  # without mujoco, that is the one-line error reported first
    Case("synth/overwrite-unrelated", prepared(robot_track_with_thesis, cli(
        "synth", "--track", "robot", "--out", "{t}/d", "--overwrite")), CLEAR, "did not write",
        requires=mujoco_renders),
    Case("synth/other-track-kept", prepared(lambda t: (t / "d/hand/scene_0000").mkdir(parents=True), cli(
        "synth", "--track", "robot", "--out", "{t}/d", "--scenes", "1", "--frames", "3", "--size", "64x48", "--quiet")),
        CORRECT, check=lambda o, t: (t / "d/hand/scene_0000").is_dir() and (t / "d/robot/scene_0000/gt.png").is_file(),
        requires=mujoco_renders),
    # ---- benchmark
    Case("benchmark/option-int", cli("benchmark", "--data", "{a}/data", "--methods", "motionbits", "--quiet",
                                     "--option", "motionbits.n_nodes=400", "--option", "motionbits.max_side=160"),
         CORRECT, check=lambda o, t: "motionbits" in o.out and "robot" in o.out),
    Case("benchmark/option-bool-bad", cli("benchmark", "--data", "{a}/data", "--methods", "motionbits",
                                          "--option", "motionbits.exact=maybe"), CLEAR, "true or false"),
    Case("benchmark/option-int-bad", cli("benchmark", "--data", "{a}/data", "--methods", "motionbits",
                                         "--option", "motionbits.n_nodes=lots"), CLEAR, "integer"),
    Case("benchmark/option-range-bad", cli("benchmark", "--data", "{a}/data", "--methods", "motionbits",
                                           "--option", "motionbits.n_nodes=3"), CLEAR, "n_nodes"),
    Case("benchmark/option-unknown-field", cli("benchmark", "--data", "{a}/data", "--methods", "motionbits",
                                               "--option", "motionbits.nodes=3"), CLEAR, "unknown MotionBitsConfig field"),
    Case("benchmark/option-baseline-bad", cli("benchmark", "--data", "{a}/data", "--methods", "flow-cc",
                                              "--option", "flow-cc.threshold=high"), CLEAR, "flow-cc"),
    Case("benchmark/option-baseline-unknown", cli("benchmark", "--data", "{a}/data", "--methods", "flow-cc",
                                                  "--option", "flow-cc.bogus=1"), CLEAR, "bogus"),
    Case("benchmark/option-malformed", cli("benchmark", "--data", "{a}/data", "--option", "nonsense"), CLEAR, "METHOD.KEY=VALUE"),
    Case("benchmark/option-not-in-methods", cli("benchmark", "--data", "{a}/data", "--methods", "flow-cc",
                                                "--option", "motionbits.exact=true"), CLEAR, "not in --methods"),
    Case("benchmark/max-scenes-0", cli("benchmark", "--data", "{a}/data", "--max-scenes", "0"), CLEAR, "--max-scenes"),
    Case("benchmark/max-scenes-negative", cli("benchmark", "--data", "{a}/data", "--max-scenes", "-1"), CLEAR, "--max-scenes"),
    Case("benchmark/no-data", cli("benchmark"), CLEAR, "--data"),
    Case("benchmark/data-missing", cli("benchmark", "--data", "{t}/nope", "--methods", "flow-cc"), CLEAR, "nope"),
    Case("benchmark/data-not-moribo", cli("benchmark", "--data", "{a}/frames", "--methods", "flow-cc"), CLEAR, "no MoRiBo scene"),
    Case("benchmark/gt-wrong-size", cli("benchmark", "--data", "{a}/data_bad_gt", "--methods", "flow-cc", "--quiet"),
         CLEAR, "gt.png is 160x60 but the frames are 160x120"),  # was: blamed the method
    Case("benchmark/frames-mixed-sizes", cli("benchmark", "--data", "{a}/data_mixed_frames", "--methods", "flow-cc",
                                             "--quiet"), CLEAR, "frame 00001.png is 160x100"),  # was: no scene named
    Case("benchmark/one-frame-scene", cli("benchmark", "--data", "{a}/data_one_frame", "--methods", "flow-cc", "--quiet"),
         CLEAR, "flow-cc failed on scene robot/scene_0000"),  # was: "need at least 2 frames ..." (which scene?)
    Case("benchmark-api/float-prediction", api(lambda t: __import__("motionbits.eval.benchmark").eval.benchmark.run_benchmark(
        t.parent / "assets" / "data", {"half": lambda frames: np.full(frames[0].shape[:2], 0.9)}, progress=False)),
         CLEAR, "integer dtype"),  # was: truncated to an all-background map and scored
    Case("benchmark/unknown-method", cli("benchmark", "--data", "{a}/data", "--methods", "magic"), CLEAR, "unknown method"),
    Case("benchmark/json-is-a-folder", prepared(lambda t: (t / "j").mkdir(), cli(
        "benchmark", "--data", "{a}/data", "--methods", "flow-cc", "--json", "{t}/j")), CLEAR, "is a folder"),
    Case("benchmark/save-pred-not-empty", prepared(unrelated_files, cli(
        "benchmark", "--data", "{a}/data", "--methods", "flow-cc", "--save-pred", "{t}/out")), CLEAR, "--overwrite"),
    Case("benchmark/save-pred-empty", in_tmp(cli("benchmark", "--data", "{a}/data", "--methods", "flow-cc", "--quiet",
                                                 "--save-pred", "")), CLEAR,
         "--save-pred is empty"),  # was: ran, saved nothing, exit 0
    Case("benchmark/save-pred", cli("benchmark", "--data", "{a}/data", "--methods", "flow-cc", "--quiet",
                                    "--save-pred", "{t}/sp"),
         CORRECT, check=lambda o, t: (t / "sp/flow-cc/robot/scene_0000.png").is_file()),
    # ---- compare
    Case("compare/scene-not-scored", prepared(a_json("a.json", {"per_scene": {"robot/scene_0000": {}}}), cli(
        "compare", "{t}/a.json", "{t}/a.json")), CLEAR, "is not scored"),  # was: KeyError 'instances' traceback
    Case("compare/method-without-scores", prepared(a_json("a.json", {"methods": {"m": {}}}), cli(
        "compare", "{t}/a.json", "{t}/a.json")), CLEAR, "has no 'per_scene'"),  # was: KeyError 'per_scene' traceback
    Case("compare/level-1.5", prepared(a_json("a.json", {"per_scene": {"robot/scene_0000": {
        "instances": [{"gt": 1, "IoU": 0.5}], "false_positives": {"spurious": 0}}}}), cli(
        "compare", "{t}/a.json", "{t}/a.json", "--level", "1.5")), CLEAR,
         "--level must be in (0, 1), got 1.5"),  # was: "level must be in (0, 1)" (the parameter, not the option)
    Case("compare/iou-null", prepared(a_json("a.json", {"per_scene": {"robot/scene_0000": {
        "instances": [{"gt": 1, "IoU": None}], "false_positives": {"spurious": 0}}}}), cli(
        "compare", "{t}/a.json", "{t}/a.json")), CLEAR,
         "body 1 has IoU None; an IoU is a number in [0, 1]"),  # was: mIoU nan, delta +nan, exit 0
    Case("compare/iou-above-1", prepared(a_json("a.json", {"per_scene": {"robot/scene_0000": {
        "instances": [{"gt": 1, "IoU": 7}], "false_positives": {"spurious": 0}}}}), cli(
        "compare", "{t}/a.json", "{t}/a.json")), CLEAR,
         "has IoU 7"),  # was: mIoU 700.0, exit 0
    Case("compare/spurious-str", prepared(a_json("a.json", {"per_scene": {"robot/scene_0000": {
        "instances": [{"gt": 1, "IoU": 0.5}], "false_positives": {"spurious": "x"}}}}), cli(
        "compare", "{t}/a.json", "{t}/a.json")), CLEAR,
         "has spurious 'x'"),  # was: "the resolved dtypes are not compatible with add.reduce"
    Case("compare/not-utf8", prepared(lambda t: (t / "a.json").write_bytes(b"\x00\xdb\xff" * 20), cli(
        "compare", "{t}/a.json", "{t}/a.json")), CLEAR,
         "a.json is not a text file"),  # was: "'utf-8' codec can't decode byte 0xdb ..." (no file named)
    # ---- scenes
    Case("scenes/out-empty", prepared(a_sequence(), in_tmp(cli("scenes", "davis", "{t}/seq", "--out", "", "--length", "3"))),
         CLEAR, "--out is empty", absent=("seq_00000",)),  # was: scenes written into the current folder, exit 0
    Case("scenes/frames-mixed-sizes", prepared(a_sequence(mixed=True), cli(
        "scenes", "davis", "{t}/seq", "--out", "{t}/o", "--length", "3", "--stride", "3")), CLEAR,
         "00001.png is 100x80", absent=("o",)),  # was: a scene of 160x120 and 100x80 frames written, exit 0
    Case("scenes/length-0", prepared(a_sequence(), cli("scenes", "davis", "{t}/seq", "--out", "{t}/o", "--length", "0")),
         CLEAR, "--length must be >= 2, got 0", absent=("o",)),  # was: "need length >= 2, ..." (the parameter, not the option)
    Case("scenes/stride-0", prepared(a_sequence(), cli("scenes", "davis", "{t}/seq", "--out", "{t}/o", "--stride", "0")),
         CLEAR, "--stride must be >= 1, got 0", absent=("o",)),  # was: "need length >= 2, stride >= 1, ..." (no option named)
    # ---- batch
    Case("batch/out-empty", in_tmp(cli("batch", "{a}/clip.mp4", "--out", "", "--workers", "1", *SEG)), CLEAR,
         "--out is empty", absent=("batch.jsonl", "clip")),  # was: clip/ and batch.jsonl written into the current folder, exit 0
    Case("batch/input-empty", prepared(lambda t: (t / "c.mp4").write_bytes((t.parent / "assets" / "clip.mp4").read_bytes()),
                                       in_tmp(cli("batch", "", "--out", "{t}/o", "--workers", "1", *SEG))), CLEAR,
         "input path is empty", absent=("o",)),  # was: every video under the current folder segmented
    Case("batch/engine-ray-without-ray", cli("batch", "{a}/clip.mp4", "--out", "{t}/o", "--engine", "ray",
                                             patches=(without("ray"),)), CLEAR, "pip install 'motionbits[ray]'",
         absent=("o",)),  # was: the same error, after an empty o/ was made
    Case("batch/out-is-a-file", prepared(a_file("o"), cli("batch", "{a}/clip.mp4", "--out", "{t}/o")), CLEAR,
         "is a file, not a folder"),  # was: "[Errno 17] File exists"
    Case("batch-api/videos-named-like-batch-files", api(lambda t: [i.name for i in __import__(
        "motionbits.batch").batch.expand_inputs([str(_copy(t, "clip.mp4", "batch.jsonl.mp4")),
                                                 str(_copy(t, "clip.mp4", ".partial.mp4"))])]),
         CORRECT, check=lambda o, t: [n[:-9] for n in o.value] == ["batch.jsonl", ".partial"]
         and all(n[-9] == "-" for n in o.value)),  # stem-<8 hex>
    # was: named batch.jsonl (its output renamed over the journal: "[Errno 21] Is a directory") and
    # .partial (its output renamed onto the folder of unfinished outputs: the video failed)
    Case("batch-api/expand-inputs-str", api(lambda t: __import__("motionbits.batch").batch.expand_inputs(
        "clip.mp4", cwd=t.parent / "assets")), CLEAR, "items must be a list of inputs"),
    # was: read letter by letter ("input not found: c"; "/..." searched the whole file system)
    Case("batch-api/run-batch-items-str", api(lambda t: __import__("motionbits.batch").batch.run_batch(
        [str(t.parent / "assets" / "clip.mp4")], str(t / "o"))), CLEAR, "items must be a list of BatchInput",
         absent=("o",)),  # was: AttributeError "'str' object has no attribute 'path'" after o/ was made
    Case("batch-api/run-batch-unknown-option", api(lambda t: _run_batch(t, ["clip.mp4"], options={"nodez": 400})),
         CLEAR, "unknown segment option(s) 'nodez'", absent=("o",)),  # was: ignored, the default nodes used
    Case("batch-api/run-batch-bad-option", api(lambda t: _run_batch(t, ["clip.mp4"], options={"nodes": 0})),
         CLEAR, "n_nodes=0", absent=("o",)),  # was: every video started, then recorded as failed
    Case("batch-api/run-batch-one-name-twice", api(lambda t: _run_batch(t, [
        __import__("motionbits.batch").batch.BatchInput(str(t.parent / "assets" / p), "c")
        for p in ("clip.mp4", "clip.avi")])), CLEAR, "two videos of name 'c'", absent=("o",)),
    # was: the second output replaced the first, both recorded as done with output o/c
    Case("batch-api/run-batch-repeat-runs-once", api(lambda t: _run_batch(t, ["clip.mp4", "clip.mp4"])),
         CORRECT, check=lambda o, t: (o.value.done, len((t / "o" / "batch.jsonl").read_text().splitlines())) == (1, 1)),
    # was: segmented twice, two records, done=2 for one video
    Case("batch-api/run-batch-out-empty", in_tmp(api(lambda t: _run_batch(t, ["clip.mp4"], out=""))), CLEAR,
         "out_dir must name the batch folder", absent=("batch.jsonl", "clip")),
    # was: clip/ and batch.jsonl written into the current folder
    Case("batch-api/run-batch-workers-fraction", api(lambda t: _run_batch(t, ["clip.mp4"], workers=1.5)), CLEAR,
         "workers must be a whole number", absent=("o",)),  # was: "'float' object cannot be interpreted as an integer"
    # ---- stack (checked before the trials: minutes of simulation)
    Case("stack/json-empty", cli("stack", "--json", ""), CLEAR,
         "--json is empty"),  # was: ran every trial, wrote no JSON, exit 0
    Case("stack/json-is-a-folder", prepared(lambda t: (t / "j").mkdir(), cli("stack", "--json", "{t}/j")), CLEAR,
         "is a folder"),  # was: "[Errno 21] Is a directory" after every trial
    Case("stack/video-empty", in_tmp(cli("stack", "--video", "")), CLEAR,
         "--video is empty"),  # was: the trial videos written into the current folder
    Case("stack/video-is-a-file", prepared(a_file("v"), cli("stack", "--video", "{t}/v")), CLEAR,
         "is a file, not a folder"),  # was: "[Errno 17] File exists" after the first trial
    Case("stack/seed-negative", cli("stack", "--seed", "-1"), CLEAR,
         "--seed must be >= 0, got -1"),  # was: "expected non-negative integer" (no option named)
    Case("stack/method-twice", cli("stack", "--trials", "1", "--methods", "gt,gt", "--quiet", "--json", "{t}/s.json"),
         CORRECT, check=lambda o, t: json.loads((t / "s.json").read_text())["methods"]["gt"]["trials"] == 1,
         requires=mujoco_renders),  # was: 2 trials in gt's row for --trials 1 (each run twice)
    # ---- motionbits API: config
    Case("stacking-api/methods-str", api(lambda t: __import__("motionbits.stacking").stacking.run_stacking(
        "gt", 1, 0, progress=None)), CLEAR, "methods must be a list"),  # was: KeyError "unknown method 'g'"
    Case("stacking-api/trials-true", api(lambda t: __import__("motionbits.stacking").stacking.run_stacking(
        ["gt"], True, 0, progress=None)), CLEAR, "trials must be a whole number"),  # was: 1 trial run
    Case("stacking-api/seed-fraction", api(lambda t: __import__("motionbits.stacking").stacking.run_stacking(
        ["gt"], 1, 1.5, progress=None)), CLEAR, "seed must be a whole number"),  # was: run, TrialResult(seed=1.5)
    Case("stacking-api/heightmap-res-0", api(lambda t: __import__("motionbits.stacking").stacking.HeightMap(
        np.zeros((4, 5, 3)), res=0)), CLEAR, "res must be a finite number"),  # was: ZeroDivisionError
    Case("stacking-api/world-grasp-mask-float", api(lambda t: __import__("motionbits.stacking").stacking.world_grasp(
        np.ones((4, 5)), np.zeros((4, 5, 3)))), CLEAR, "mask must be an (H, W) bool"),
    # was: IndexError "arrays used as indices must be of integer (or boolean) type"
    Case("stacking-api/trial-config-width-0", api(lambda t: __import__("motionbits.stacking").stacking.TrialConfig(
        width=0)), CLEAR, "width must be in [32, 16384]"),  # was: accepted (MuJoCo failed minutes later)
    Case("stacking-api/trial-config-frame-dt-0", api(lambda t: __import__("motionbits.stacking").stacking.TrialConfig(
        frame_dt=0)), CLEAR, "frame_dt must be > 0"),  # was: accepted (1 / frame_dt for the video)
    Case("stacking-api/summarise-none", api(lambda t: __import__("motionbits.stacking").stacking.summarise(None)),
         CLEAR, "results must be a dict"),  # was: AttributeError "'NoneType' object has no attribute 'items'"
    Case("stacking-api/format-table-empty", api(lambda t: __import__("motionbits.stacking").stacking.format_table({})),
         CLEAR, "summary must be a dict as summarise returns"),  # was: KeyError 'methods'
    Case("stacking-api/format-table-unknown-failure", api(lambda t: __import__("motionbits.stacking").stacking.format_table(
        {"methods": {"gt": {"success": 0, "trials": 1, "stacked_mean": 0.0, "stacked_total": 0,
                            "failures": {"timeout": 1}}}})), CLEAR,
         "['failures'] must map failure reasons (grasp, stack, masks)"),  # was: ValueError "'timeout' is not in tuple"
    Case("refine/build-prompts-float-labels", api(lambda t: __import__("motionbits.refine_sam2").refine_sam2.build_prompts(
        _LAB.astype(float), np.zeros((4, 4), int))), CLEAR,
         "labels must have an integer dtype"),  # was: TypeError "'numpy.float64' object cannot be interpreted as an integer"
    Case("refine/node-centres-rows-0", api(lambda t: __import__("motionbits.refine_sam2").refine_sam2.node_centres(
        (20, 20), 0, 4)), CLEAR, "rows must be >= 1"),  # was: ZeroDivisionError
    Case("refine/judge-float-mask", api(lambda t: __import__("motionbits.refine_sam2").refine_sam2.judge_refinement(
        (_LAB == 3).astype(float), _LAB == 3, _LAB == 0, 2.0, min_iou=0.5, max_outside=0.1)), CLEAR,
         "refined must be an (H, W) bool"),  # was: TypeError "ufunc 'bitwise_and' not supported for the input types"
    Case("refine/refiner-min-iou-nan", api(lambda t: __import__("motionbits.refine_sam2").refine_sam2.Sam2Refiner(
        None, None, min_iou=float("nan"))), CLEAR, "min_iou must be a number in [0, 1]"),
    # was: accepted (NaN compares false: every refined mask accepted)
    Case("api/config-n_nodes-str", api(lambda t: _config(n_nodes="10000")), CLEAR, "n_nodes"),
    Case("api/config-n_nodes-bool", api(lambda t: _config(n_nodes=True)), CLEAR, "n_nodes"),
    Case("api/config-n_nodes-float", api(lambda t: _config(n_nodes=100.5)), CLEAR, "n_nodes"),
    Case("api/config-inflation-nan", api(lambda t: _config(mcl_inflation=float("nan"))), CLEAR, "mcl_inflation"),
    Case("api/config-exact-str", api(lambda t: _config(exact="false")), CLEAR, "exact"),
    Case("api/config-max_side-huge", api(lambda t: _config(max_side=100000)), CLEAR, "max_side"),
    Case("api/config-seed_fraction-0", api(lambda t: _config(seed_fraction=0.0)), CLEAR, "seed_fraction"),
    Case("api/config-backend-unknown", api(lambda t: _config(backend="cuda")), CLEAR, "backend"),
    Case("api/config-flow-int", api(lambda t: _config(flow=3)), CLEAR, "flow"),
    Case("api/config-unknown-field", api(lambda t: _config(nodes=10)), CLEAR, "nodes"),
    Case("api/config-with-bad", api(lambda t: _config().with_(k_neighbors=0)), CLEAR, "k_neighbors"),
    Case("api/config-numpy-int", api(lambda t: _config(n_nodes=np.int64(900))), CORRECT,
         check=lambda o, t: o.value.n_nodes == 900),
    Case("api/segmenter-config-dict", api(lambda t: _segment(_F[:1], {"n_nodes": 400})), CLEAR,
         "config must be a MotionBitsConfig"),  # was: "'dict' object has no attribute 'flow'"
    # ---- motionbits API: frames and flow
    Case("api/max_side-huge-small-input", api(lambda t: _work_size((120, 160), _config(max_side=16384))),
         CORRECT, check=lambda o, t: o.value == ((120, 160), (480, 640))),  # up to 640 only
    Case("api/max_side-huge-large-input", api(lambda t: _work_size((900, 1200), _config(max_side=16384))),
         CORRECT, check=lambda o, t: o.value == ((900, 1200), (900, 1200))),  # never beyond the input
    Case("api/max_side-small", api(lambda t: _work_size((120, 160), _config(max_side=80))),
         CORRECT, check=lambda o, t: o.value == ((120, 160), (60, 80))),
    Case("api/flow-wrong-shape", api(lambda t: _segment(_F, _small_config(), _flow_returning(
        lambda p: np.zeros((10, 10, 2), np.float32)))), CLEAR, "flow backend"),
    Case("api/flow-nan", api(lambda t: _segment(_F, _small_config(), _flow_returning(
        lambda p: np.full((*p.shape[:2], 2), np.nan, np.float32)))), CLEAR, "NaN"),
    Case("api/flow-inf", api(lambda t: _segment(_F, _small_config(), _flow_returning(
        lambda p: np.full((*p.shape[:2], 2), np.inf, np.float32)))), CLEAR, "infinite"),
    Case("api/flow-returns-list", api(lambda t: _segment(_F, _small_config(), _flow_returning(
        lambda p: [[0.0, 0.0]]))), CLEAR, "flow backend"),
    Case("api/flow-float64-ok", api(lambda t: _segment(_F, _small_config(), _flow_returning(
        lambda p: np.zeros((*p.shape[:2], 2), np.float64)))), CORRECT, check=lambda o, t: len(o.value) == 3),
    Case("api/frame-8x4000", api(lambda t: _segment([np.zeros((8, 4000, 3), np.uint8)] * 2)), CLEAR, "20 px"),
    Case("api/frame-nan-float", api(lambda t: _segment([np.full((64, 64, 3), np.nan)])), CLEAR, "uint8"),
    Case("api/frame-float-0-255", api(lambda t: _segment([_F[0].astype(np.float64)])), CLEAR,
         "np.clip(img, 0, 255)"),  # not the [0, 1] recipe, which would turn it white
    Case("api/frame-float-nan-hint", api(lambda t: _segment([np.full((64, 64, 3), np.nan, np.float32)])), CLEAR,
         "NaN"),
    Case("api/frame-uint16-scaled", api(lambda t: __import__("motionbits.video").video.as_rgb_frame(
        np.dstack([_GRAD16] * 3))), CORRECT, check=lambda o, t: o.value.max() == round(_GRAD16.max() / 257)),
    Case("api/frame-wrong-shape", api(lambda t: _segment([np.zeros((64, 64, 2), np.uint8)])), CLEAR, "shape"),
    Case("api/frame-channels-first", api(lambda t: _segment([np.ascontiguousarray(_F[0].transpose(2, 0, 1))])),
         CLEAR, "channels-first (C, H, W): pass frame.transpose(1, 2, 0)"),  # a torch tensor's layout
    Case("api/frame-none", api(lambda t: _segment([None])), CLEAR, "numpy array"),
    Case("api/size-change", api(lambda t: _segment([_F[0], _F[1][:100]], _small_config())), CLEAR, "call reset()"),
    Case("api/segment-video-every-0", api(lambda t: list(__import__("motionbits").segment_video(_F, every=0))), CLEAR, "every"),
    Case("api/segment-video-every-float", api(lambda t: list(__import__("motionbits").segment_video(_F, every=1.5))),
         CLEAR, "every"),  # was: frames 0, 3, 6, ... kept by i % 1.5 == 0
    Case("api/segment-video-every-str", api(lambda t: list(__import__("motionbits").segment_video(_F, every="2"))),
         CLEAR, "every"),
    Case("api/segment-video-one-rgb-frame", api(lambda t: list(__import__("motionbits").segment_video(_F[0]))), CLEAR,
         "pass [frame] or frame[None]"),  # was: "frame 0 is too small to segment: 3x160 pixels"
    Case("api/iter-frames-bytes-path", api(lambda t: list(__import__("motionbits.video").video.iter_frames(
        str(t / "x.mp4").encode()))), CLEAR, "os.fsdecode"),
    Case("api/sample-indices-float", api(lambda t: __import__("motionbits").sample_frame_indices(10, 2.5)), CLEAR,
         "num_frames must be a whole number"),  # was: "'float' object cannot be interpreted as an integer"
    Case("api/sample-indices-bool", api(lambda t: __import__("motionbits").sample_frame_indices(10, True)), CLEAR,
         "num_frames"),  # was: [9], True read as 1 frame
    Case("api/sample-indices-nan", api(lambda t: __import__("motionbits").sample_frame_indices(10, float("nan"))),
         CLEAR, "num_frames"),
    Case("api/sample-indices-whole-float", api(lambda t: __import__("motionbits").sample_frame_indices(10, 4.0)),
         CORRECT, check=lambda o, t: o.value == [0, 3, 6, 9]),  # a UI slider's 4.0 (was: TypeError)
    Case("api/iter-frames-int", api(lambda t: list(__import__("motionbits.video").video.iter_frames(123))), CLEAR, "unsupported"),
    Case("api/read-image-16bit", api(lambda t: (Image.fromarray(_GRAD16).save(t / "g.png"),
                                               __import__("motionbits.video").video.read_image(t / "g.png"))[1]),
         CORRECT, check=lambda o, t: o.value.shape == (64, 64, 3) and o.value.max() == round(_GRAD16.max() / 257)
         and o.value.min() == 0),
    Case("api/read-image-corrupt", api(lambda t: ((t / "c.png").write_bytes(b"garbage"),
                                                 __import__("motionbits.video").video.read_image(t / "c.png"))),
         CLEAR, "could not read image"),
    # ---- motionbits API: objects and grasps
    Case("api/instance-from-mask-id-fraction", api(lambda t: __import__("motionbits").instance_from_mask(_LAB == 3, 2.7)),
         CLEAR, "id must be a whole number"),  # was: an Instance of id 2
    Case("api/instance-from-mask-id-0", api(lambda t: __import__("motionbits").instance_from_mask(_LAB == 3, 0)),
         CLEAR, "id must be >= 1 (0 is the background)"),  # was: an Instance of id 0 (the background)
    Case("api/labels-from-instances-id-huge", api(lambda t: __import__("motionbits").labels_from_instances(
        [__import__("dataclasses").replace(__import__("motionbits").instance_from_mask(_LAB == 3, 3), id=2**40)], (20, 20))),
         CLEAR, "does not fit the int32 label map"),  # was: OverflowError traceback from numpy
    Case("api/labels-from-instances-id-negative", api(lambda t: __import__("motionbits").labels_from_instances(
        [__import__("dataclasses").replace(__import__("motionbits").instance_from_mask(_LAB == 3, 3), id=-1)], (20, 20))),
         CLEAR, "objects[0].id must be >= 1"),  # was: a label map holding id -1
    Case("api/labels-from-instances-masks", api(lambda t: __import__("motionbits").labels_from_instances([_LAB == 3], (20, 20))),
         CLEAR, "objects[0] is ndarray, not an Instance"),  # was: AttributeError 'numpy.ndarray' object has no attribute 'get_mask'
    Case("api/decode-rle-negative-size", api(lambda t: __import__("motionbits").decode_rle({"size": [-2, 2], "counts": [1, 2]})),
         CLEAR, "rle['size'] must be [H, W]",
         requires=lambda: None if __import__("importlib").util.find_spec("pycocotools") else "pycocotools not installed"),
    # was: OverflowError "can't convert negative value to siz" traceback from pycocotools
    Case("api/grasp-min-area-nan", api(lambda t: __import__("motionbits").grasp_proposals(_LAB, min_area=float("nan"))),
         CLEAR, "min_area must be a whole number"),  # was: [] (no region passes c >= nan)
    Case("api/grasp-min-area-fraction", api(lambda t: __import__("motionbits").grasp_proposals(_LAB, min_area=1.5)),
         CLEAR, "min_area must be a whole number"),  # was: accepted as 1.5 pixels
    Case("api/grasp-negative-labels", api(lambda t: __import__("motionbits").grasp_proposals(-_LAB)),
         CLEAR, "negative ids"),  # was: grasps of objects -3 and -5
    Case("api/instance-from-mask-nan", api(lambda t: __import__("motionbits").instance_from_mask(
        np.where(_LAB == 3, 1.0, np.nan), 3)), CLEAR, "mask holds NaN"),  # was: an Instance of the whole image
    Case("api/grasp-mask-nan", api(lambda t: __import__("motionbits").grasp_from_mask(np.where(_LAB == 3, 1.0, np.nan))),
         CLEAR, "mask holds NaN"),  # was: a grasp of the whole image (NaN is non-zero)
    # ---- motionbits API: eval
    Case("eval-api/20000-ids", api(lambda t: _eval_many(20_000, (200, 200))), CORRECT,
         check=lambda o, t: o.value.n_gt == 20_000 and o.value.f1.min() == 1.0, limit=20),
    Case("eval-api/shape-mismatch", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        np.zeros((5, 6), int), np.zeros((6, 5), int))), CLEAR, "shape"),
    Case("eval-api/float-map", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        np.zeros((5, 5), np.float32), np.zeros((5, 5), int))), CLEAR, "integer"),
    Case("eval-api/negative-labels", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        -np.ones((5, 5), int), np.zeros((5, 5), int))), CLEAR, "negative"),
    Case("eval-api/huge-ids", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        _LAB * 10**12, _LAB)), CORRECT, check=lambda o, t: o.value.f1.tolist() == [1.0, 1.0]),
    Case("eval-api/ari-shape-mismatch", api(lambda t: __import__("motionbits.eval").eval.adjusted_rand_index(
        np.zeros((10, 40), int), _LAB)), CLEAR, "differ in shape"),  # was: 0.0 (same size, compared pixel by pixel)
    Case("eval-api/write-label-map-jpg", api(lambda t: __import__("motionbits.eval").eval.write_label_map(
        t / "gt.jpg", _LAB * 1000)), CLEAR, "must end in .png",
        absent=("gt.jpg",)),  # was: wrote an 8-bit JPEG (ids 3000 and 5000 read back as 255)
    Case("eval-api/boundary-tolerance-negative", api(lambda t: __import__("motionbits.eval").eval.boundary_tolerance(
        (480, 640), -0.01)), CLEAR, "fraction must be a finite number >= 0"),  # was: -8 pixels
    Case("eval-api/summarize-dicts", api(lambda t: __import__("motionbits.eval").eval.summarize([{"IoU": 0.5}])),
         CLEAR, "frames[0] is dict"),  # was: AttributeError 'dict' object has no attribute 'n_gt' traceback
    Case("eval-api/boundary-map-valid-shape", api(lambda t: __import__("motionbits.eval").eval.boundary_map(
        _LAB, np.ones((10, 40), bool))), CLEAR, "valid has shape (10, 40), the label map (20, 20)"),  # was: numpy broadcast error
    Case("eval-api/tolerance-negative", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        _LAB, _LAB, tolerance=-1)), CLEAR, "tolerance must be >= 0"),  # was: "negative dimensions are not allowed"
    Case("eval-api/tolerance-fraction", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        _LAB, _LAB, tolerance=1.5)), CLEAR, "tolerance must be a whole number"),  # was: read as 1 px
    Case("eval-api/tolerance-huge", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        np.roll(_LAB, 1, axis=0), _LAB, tolerance=10**6).bf1.tolist()), CORRECT,
         check=lambda o, t: o.value == [1.0, 1.0]),  # was: MemoryError "Unable to allocate 58.2 TiB"
    Case("eval-api/boundary-tolerance-1d-shape", api(lambda t: __import__("motionbits.eval").eval.boundary_tolerance((480,))),
         CLEAR, "shape must be (H, W, ...)"),  # was: IndexError traceback
    Case("eval-api/ignore-nan", api(lambda t: __import__("motionbits.eval").eval.evaluate_frame(
        _LAB, _LAB + 1, np.full(_LAB.shape, np.nan))), CLEAR,
         "ignore mask holds NaN"),  # was: every pixel ignored (NaN is True), perfect scores
    Case("eval-api/ari-float", api(lambda t: __import__("motionbits.eval").eval.adjusted_rand_index(
        _LAB + 0.5, _LAB)), CLEAR, "whole-number labels"),  # was: 1.0 (3.5 and 5.5 read as labels)
    Case("eval-api/ari-negative", api(lambda t: __import__("motionbits.eval").eval.adjusted_rand_index(
        -_LAB, _LAB)), CLEAR, "negative labels"),  # was: 1.0 (-1, void, read as a label)
    Case("eval-api/body-kinds-meta-nested-deep", api(lambda t: ((t / "meta.json").write_text("[" * 100_000),
                                                             __import__("motionbits.eval.kinds").eval.kinds.body_kinds(t))[1]),
         CORRECT, check=lambda o, t: o.value == {}),  # was: RecursionError traceback (documented: not JSON -> {})
    Case("eval-api/body-kinds-one-bad-id", api(lambda t: ((t / "meta.json").write_text(json.dumps(
        {"labels": {"1": {"kind": "box"}, "1.5": {"kind": "cup"}}})),
        __import__("motionbits.eval.kinds").eval.kinds.body_kinds(t))[1]),
        CORRECT, check=lambda o, t: o.value == {1: "box"}),  # was: {} (one bad id dropped every kind)
    Case("flow-api/raft-from-file-none", api(lambda t: __import__("motionbits.flow_raft").flow_raft.RAFTFlow.from_file(
        None)), CLEAR, "RAFT weights must be a file path"),  # was: "expected str, bytes or os.PathLike object"
    Case("flow-api/raft-from-file-folder", api(lambda t: __import__("motionbits.flow_raft").flow_raft.RAFTFlow.from_file(
        t)), CLEAR, "is a folder"),  # was: "RAFT weights file '...' does not exist" (it does: a folder)
    Case("flow-api/raft-from-spec-none", api(lambda t: __import__("motionbits.flow_raft").flow_raft.RAFTFlow.from_spec(
        None)), CLEAR, "a RAFT flow spec is 'raft:PATH'"),  # was: AttributeError "'NoneType' ... 'partition'"
    Case("synth-api/demo-clip-n-frames-fraction", api(lambda t: __import__("motionbits.synth").synth.demo_clip(
        n_frames=2.5, size=(40, 50))), CLEAR, "n_frames must be a whole number"),
    # was: "'float' object cannot be interpreted as an integer"
    Case("synth-api/demo-clip-size-int", api(lambda t: __import__("motionbits.synth").synth.demo_clip(
        n_frames=2, size=40)), CLEAR, "size must be (height, width)"),  # was: "'int' object is not subscriptable"
    Case("synth-api/demo-clip-size-huge", api(lambda t: __import__("motionbits.synth").synth.demo_clip(
        n_frames=2, size=(10**6, 10**6))), CLEAR, "size must be at most"),  # was: MemoryError
    Case("synth-api/render-clip-too-long", api(lambda t: __import__("motionbits.synth").synth.render_planar_clip(
        [], size=(480, 640), n_frames=10**5)), CLEAR, "n_frames x height x width must be at most"),
    # was: 215 GB of frames and labels asked for (a MemoryError, or swapping)
    Case("synth-api/render-size-0", api(lambda t: __import__("motionbits.synth").synth.render_planar_clip(
        [], size=(0, 0), n_frames=2)), CLEAR, "size must be (height, width)"),  # was: OpenCV "inv_scale_x > 0"
    Case("synth-api/render-seed-negative", api(lambda t: __import__("motionbits.synth").synth.render_planar_clip(
        [], size=(20, 20), n_frames=2, seed=-1)), CLEAR, "seed must be >= 0"),  # was: "expected non-negative integer"
    Case("synth-api/render-noise-nan", api(lambda t: __import__("motionbits.synth").synth.render_planar_clip(
        [], size=(20, 20), n_frames=2, noise=float("nan"))), CLEAR, "noise must be finite"),  # was: black frames
    Case("synth-api/body-omega-nan", api(lambda t: __import__("motionbits.synth").synth.Body(
        (__import__("motionbits.synth").synth.Polygon.rect(1, 1, 9, 9),), omega=float("nan"))), CLEAR,
         "omega must be finite"),  # was: the body vanished from every frame, labels all 0
    Case("synth-api/bodies-are-polygons", api(lambda t: __import__("motionbits.synth").synth.render_planar_clip(
        [__import__("motionbits.synth").synth.Polygon.rect(1, 1, 9, 9)], size=(20, 20), n_frames=2)), CLEAR,
         "bodies must be a list of Body"),  # was: AttributeError "'Polygon' ... 'polygons'"
    Case("synth-api/polygon-empty", api(lambda t: __import__("motionbits.synth").synth.Polygon(())), CLEAR,
         "at least 3 (x, y) pairs"),  # was: OpenCV "p.checkVector(2, CV_32S) > 0" when rendered
    Case("synth-api/polygon-huge-coords", api(lambda t: __import__("motionbits.synth").synth.Polygon.rect(
        1, 1, 1e12, 1e12)), CLEAR, "within +-1e9 px"),  # was: int32 wrapped when drawn, 15 s
    Case("benchmark-api/max-scenes-0", api(lambda t: __import__("motionbits.eval.benchmark").eval.benchmark.run_benchmark(
        t.parent / "assets" / "data", {"zero": lambda frames: np.zeros(frames[0].shape[:2], int)}, max_scenes=0,
        progress=False)), CLEAR, "max_per_track must be >= 1"),  # was: no scene scored, every score NaN, no error
    # ---- somprompt
    Case("somprompt/draw-70000-ids", api(lambda t: _draw(_many_ids(70_000))), CORRECT,
         check=lambda o, t: (len(o.value.placements) == 256 and len(o.value.dropped) == 70_000 - 256
                             and any("69744 of 70000" in w for w in o.warns)), limit=30),
    Case("somprompt/draw-6400-ids", api(lambda t: _draw(_many_ids(6_400))), CORRECT,
         check=lambda o, t: len(o.value.placements) == 256, limit=30),
    Case("somprompt/draw-max-marks-all", api(lambda t: _draw(_LAB, max_marks=None)), CORRECT,
         check=lambda o, t: sorted(o.value.placements) == [3, 5] and not o.value.dropped),
    Case("somprompt/max-marks-0", api(lambda t: _draw(_LAB, max_marks=0)), CLEAR, "max_marks"),
    Case("somprompt/draw-shape-mismatch", api(lambda t: _draw(_LAB, shape=(30, 30))), CLEAR, "labels"),
    Case("somprompt/thickness-huge", api(lambda t: _draw(_LAB, thickness=10**9)), CLEAR,
         "thickness must be in [1, 32767]"),  # was: OpenCV's "thickness <= MAX_THICKNESS" assertion
    Case("somprompt/text-scale-inf", api(lambda t: _draw(_LAB, text_scale=float("inf"))), CLEAR,
         "text_scale must be > 0 and <= 16383.5"),  # was: OverflowError "cannot convert float infinity to integer"
    Case("somprompt/text-thickness-0", api(lambda t: __import__("somprompt").NumberAnnotator(text_thickness=0)),
         CLEAR, "text_thickness must be in [1, 32767]"),  # was: silently drawn 1 px thick
    Case("somprompt/auto-text-scale-nan", api(lambda t: __import__("somprompt").auto_text_scale((float("nan"), 4))),
         CLEAR, "shape[0] must be a whole number"),  # was: a NaN font scale
    Case("somprompt/auto-text-scale-str", api(lambda t: __import__("somprompt").auto_text_scale("ab")),
         CLEAR, "shape must be (H, W)"),  # was: "unsupported operand type(s) for /: 'str' and 'float'"
    Case("somprompt/marks-json-size-nan", api(lambda t: _marks_json(image_size=(float("nan"), 20))),
         CLEAR, "image_size[0] must be a whole number"),  # was: "cannot convert float NaN to integer"
    Case("somprompt/marks-json-indent-nan", api(lambda t: _marks_json(indent=float("nan"))),
         CLEAR, "indent must be a whole number"),  # was: "can't multiply sequence by non-int of type 'float'"
    Case("somprompt/marks-json-list", api(lambda t: _marks_json(list(__import__("somprompt").describe_marks(
        _LAB, __import__("somprompt").MarkRegistry()).values()))),
         CLEAR, "marks must be a mapping id -> MarkInfo"),  # was: AttributeError "'list' object has no attribute 'values'"
    Case("somprompt/text-padding-inf", api(lambda t: __import__("somprompt").NumberAnnotator(text_padding=float("inf"))),
         CLEAR, "text_padding must be a whole number"),  # was: OverflowError "cannot convert float infinity to integer"
    Case("somprompt/draw-uint64-huge-ids", api(lambda t: _draw(np.where(_LAB > 0, np.uint64(2**63 + 5), np.uint64(0)))),
         CLEAR, "too large for int64"),  # was: "holds negative ids (min -9223372036854775803)"
    Case("api/check-label-map-uint64-huge", api(lambda t: __import__("motionbits.objects").objects.check_label_map(
        np.full((4, 4), 2**64 - 1, np.uint64))), CLEAR, "too large"),  # was: returned ids of -1
    Case("somprompt/draw-float-labels", api(lambda t: _draw(_LAB.astype(np.float32))), CLEAR, "labels"),
    Case("somprompt/draw-on-16bit-pil", api(lambda t: _draw(np.zeros((64, 64), np.int64), scene=Image.fromarray(_GRAD16))),
         CORRECT, check=lambda o, t: np.asarray(o.value.image).max() == round(_GRAD16.max() / 257)),
    Case("somprompt/parse-huge-mark", api(lambda t: _parse("It is [999999999999] and [3].", _LAB)), CORRECT,
         check=lambda o, t: o.value.ids == [3] and o.value.unknown == ["999999999999"]),
    Case("somprompt/parse-5-digit-list", api(lambda t: _parse("objects 3, 12345 and 5", _LAB)), CORRECT,
         check=lambda o, t: o.value.ids == [3, 5] and o.value.unknown == ["12345"]),
    Case("somprompt/parse-none", api(lambda t: _parse(None)), CLEAR, "str"),
    Case("somprompt/parse-nested-list", api(lambda t: _parse("The moved ones: [3, [5]]", _LAB)), CORRECT,
         check=lambda o, t: o.value.ids == [3, 5]),  # was: [5] only
    Case("somprompt/resize-max-side-float", api(lambda t: __import__("somprompt").resize_max_side(
        np.zeros((40, 60, 3), np.uint8), 30.5)), CLEAR, "max_side must be a whole number"),  # was: resized
    Case("somprompt/resize-max-side-bool", api(lambda t: __import__("somprompt").resize_max_side(
        np.zeros((40, 60, 3), np.uint8), True)), CLEAR, "max_side must be a whole number"),  # was: 1x1 px
    Case("somprompt/parse-5000-digit-mark", api(lambda t: _parse("[" + "9" * 5000 + "] and [3]", _LAB)), CORRECT,
         check=lambda o, t: o.value.ids == [3] and o.value.unknown == ["9" * 5000]),  # was: int() digit limit
    Case("somprompt/parse-5000-digit-no-labels", api(lambda t: _parse("mark 0" + "7" * 5000)), CORRECT,
         check=lambda o, t: o.value.ids == [] and o.value.unknown == ["7" * 5000]),  # beyond int64: no mark
    Case("somprompt/parse-marks-int", api(lambda t: _parse("[3]", marks=3)), CLEAR, "marks must be"),
    Case("somprompt/parse-marks-str", api(lambda t: _parse("[3]", marks="35")), CLEAR, "marks must be"),  # was: {3, 5}
    Case("somprompt/parse-marks-none-id", api(lambda t: _parse("[3]", marks=[3, None])), CLEAR, "integer object ids"),
    Case("somprompt/mode-none", api(lambda t: _draw(_LAB, mode=None)), CLEAR, "mode must be"),  # was: not iterable
    Case("somprompt/repair-text-none", api(lambda t: __import__("somprompt").repair_text(None)), CLEAR,
         "text must be a str"),  # was: "expected string or bytes-like object, got 'NoneType'"
    Case("somprompt/masks-for-ids-none", api(lambda t: __import__("somprompt").masks_for_ids(_LAB, None)), CLEAR,
         "ids must be"),
    Case("somprompt/masks-for-ids-fraction", api(lambda t: __import__("somprompt").masks_for_ids(_LAB, [3.7])),
         CLEAR, "integer object ids"),  # was: the mask of 3
    Case("somprompt/mark-video-frame-indices-fraction", api(lambda t: __import__("somprompt").mark_video(
        [_F[0][:20, :20]] * 2, [_LAB] * 2, frame_indices=[0, 0.5])), CLEAR,
        "must hold integer frame numbers"),  # was: kept as [0, 0.5]; the registry recorded the second frame as frame 0
    Case("somprompt/write-mp4-to-folder", api(lambda t: __import__("somprompt").write_mp4(list(_F), t)), CLEAR,
         "is a folder"),  # was: PyAV's "Could not determine output format"
    Case("somprompt/write-mp4-wrong-suffix", api(lambda t: __import__("somprompt").write_mp4(list(_F), t / "v.avi")),
         CLEAR, "must end in .mp4"),
    Case("somprompt/write-mp4-fps-huge", api(lambda t: __import__("somprompt").write_mp4(list(_F), t / "v.mp4", fps=1e300)),
         CLEAR, "fps must be"),  # was: OverflowError
    Case("video/write-h264-empty-keeps-old", api(lambda t: _h264_failed_over(t, [])), CORRECT,
         check=lambda o, t: o.value == (b"an earlier video", ["v.mp4"])),  # was: the earlier file deleted
    Case("video/write-h264-mixed-sizes-keeps-old", api(lambda t: _h264_failed_over(
        t, [_F[0], _F[0][:60]])), CORRECT, check=lambda o, t: o.value == (b"an earlier video", ["v.mp4"])),
    # was: the earlier file replaced by a half-written video of the first frame
    Case("video/write-h264-fps-tiny", api(lambda t: __import__("motionbits.video_writer").video_writer.write_h264(
        list(_F), t / "v.mp4", fps=1e-6)), CLEAR, "fps must be a number >= 0.001", absent=("v.mp4",)),
    # was: written at 24 fps (the rate rounded to 0)
    Case("video/write-h264-fps-float32", api(lambda t: __import__("motionbits.video_writer").video_writer.write_h264(
        list(_F), t / "v.mp4", fps=np.float32(5))), CORRECT, check=lambda o, t: (t / "v.mp4").stat().st_size > 0),
    # was: TypeError "argument should be a string or a Rational instance"
    Case("video/h264-crf-negative", api(lambda t: __import__("motionbits.video_writer").video_writer.H264Writer(
        t / "v.mp4", crf=-5)), CLEAR, "crf must be in [0, 51]"),  # was: OverflowError from PyAV on the first frame
    Case("video/write-h264-frames-none", api(lambda t: __import__("motionbits.video_writer").video_writer.write_h264(
        None, t / "v.mp4")), CLEAR, "frames must be an iterable"),  # was: "'NoneType' object is not iterable"
    Case("video/write-h264-too-wide", api(lambda t: __import__("motionbits.video_writer").video_writer.write_h264(
        [np.zeros((2, 20000, 3), np.uint8)], t / "v.mp4")), CLEAR, "at most 16384 pixels a side",
         absent=("v.mp4",)),  # was: av ExternalError "Generic error in an external library"
    Case("video/write-h264-parent-is-file", api(lambda t: (a_file("f")(t), __import__(
        "motionbits.video_writer").video_writer.write_h264(list(_F), t / "f" / "v.mp4"))), CLEAR,
         "is a file, not a folder"),  # was: FileExistsError "[Errno 17] File exists: '.../f'"
    Case("somprompt/write-gif-to-folder", api(lambda t: __import__("somprompt").write_gif(list(_F), t)), CLEAR,
         "is a folder"),  # was: PIL's "unknown file extension: "
    Case("somprompt/write-gif-fps-tiny", api(lambda t: __import__("somprompt").write_gif(list(_F), t / "v.gif", fps=1e-3)),
         CLEAR, "fps must be"),  # was: OverflowError (a GIF frame lasts at most 655.35 s)
    Case("somprompt/write-gif-fps-huge", api(lambda t: __import__("somprompt").write_gif(list(_F), t / "v.gif", fps=1e6)),
         CLEAR, "<= 100", absent=("v.gif",)),  # was: wrote 0 ms frame delays (a GIF counts in 1/100 s)
    Case("somprompt/write-gif-fps-str", api(lambda t: __import__("somprompt").write_gif(list(_F), t / "v.gif", fps="10")),
         CLEAR, "fps must be"),  # was: "'>' not supported between instances of 'str' and 'int'"
    Case("somprompt/prompt-not-utf8", api(lambda t: ((t / "p.txt").write_bytes(b"\xff\xfe {question}"),
                                                      __import__("somprompt").load_prompt("p", prompts_dir=t))),
         CLEAR, "p.txt is not UTF-8"),  # was: "'utf-8' codec can't decode byte 0xff" (which file?)
    Case("somprompt/prompts-dir-is-a-file", api(lambda t: __import__("somprompt").list_prompts(
        t.parent / "assets" / "clip.mp4")), CLEAR, "is a file"),  # was: "does not exist"
    Case("somprompt/prompt-empty", api(lambda t: ((t / "p.txt").write_text("\n  \n"),
                                                  __import__("somprompt").load_prompt("p", prompts_dir=t))),
         CLEAR, "p.txt is empty"),  # was: '' returned, an empty prompt sent to the VLM
    Case("somprompt/prompt-utf8-bom", api(lambda t: ((t / "p.txt").write_bytes("\ufeffWhat moved? ${x}".encode()),
                                                     __import__("somprompt").load_prompt("p", prompts_dir=t, x=1))[1]),
         CORRECT, check=lambda o, t: o.value == "What moved? 1"),  # was: '\ufeffWhat moved? 1' (BOM in the prompt)
    Case("somprompt/prompts-dir-empty-str", api(lambda t: __import__("somprompt").list_prompts("")), CLEAR,
         "prompts_dir is empty"),  # was: the current folder's .txt files
    Case("somprompt/prompts-dir-int", api(lambda t: __import__("somprompt").load_prompt("som_vqa", prompts_dir=5)),
         CLEAR, "prompts_dir must be a folder path"),  # was: "expected str, bytes or os.PathLike object, not int"
    Case("somprompt/mark-prompt-variables-duplicate-ids", api(lambda t: __import__("somprompt").mark_prompt_variables(
        __import__("somprompt").MarkRegistry.from_label_maps([_LAB]), [3, 3, 5])), CORRECT,
         check=lambda o, t: o.value["num_marks"] == "2" and o.value["mark_list"] == "[1], [2]"),  # was: 3, "[1], [1], [2]"
    Case("somprompt/mark-list-ids-int", api(lambda t: __import__("somprompt").format_mark_list(
        __import__("somprompt").MarkRegistry.from_label_maps([_LAB]), 3)), CLEAR,
         "ids must be an iterable"),  # was: "'int' object is not iterable"
    Case("somprompt/mark-list-of-a-list", api(lambda t: __import__("somprompt").format_mark_list([1, 2])), CLEAR,
         "MarkRegistry"),  # was: "'list' object has no attribute 'ids'"
    Case("somprompt/register-fraction", api(lambda t: __import__("somprompt").MarkRegistry().register([1.5])), CLEAR,
         "whole numbers"),  # was: registered id 1
    Case("somprompt/register-none", api(lambda t: __import__("somprompt").MarkRegistry().register(None)), CLEAR,
         "ids must be an iterable"),  # was: "'NoneType' object is not iterable"
    Case("somprompt/register-whole-float-and-huge", api(lambda t: (lambda r: (r.register([3.0, 2**2000]), r.ids)[1])(
        __import__("somprompt").MarkRegistry())), CORRECT, check=lambda o, t: o.value == [3, 2**2000]),
    Case("somprompt/registry-number-fraction", api(lambda t: (lambda r: (r.register([3, 5]), r.number(3.7))[1])(
        __import__("somprompt").MarkRegistry())), CLEAR, "obj_id must be a whole number"),  # was: 1, the mark of id 3
    Case("somprompt/registry-id-for-number-fraction", api(lambda t: (lambda r: (r.register([3, 5]), r.id_for_number(1.5))[1])(
        __import__("somprompt").MarkRegistry())), CLEAR, "number must be a whole number"),  # was: 3, the id of mark 1
    Case("somprompt/registry-frames-seen-fraction", api(lambda t: (lambda r: (r.update(_LAB, frame_index=4), r.frames_seen(3.7))[1])(
        __import__("somprompt").MarkRegistry())), CLEAR, "obj_id must be a whole number"),  # was: [4], the frames of id 3
    Case("somprompt/palette-one-str", api(lambda t: __import__("somprompt").ColorPalette("#ff0000")), CLEAR,
         "ColorPalette(['#ff0000'])"),  # was: "colour '#' is not of the form '#rrggbb'" (the str read char by char)
    Case("somprompt/palette-none-colour", api(lambda t: __import__("somprompt").ColorPalette([None])), CLEAR,
         "colors must be a sequence of colours"),  # was: 'NoneType' object is not iterable
    Case("somprompt/mark-text-fraction", api(lambda t: __import__("somprompt").mark_text(1.5)), CLEAR,
         "number must be a whole number"),  # was: '1'
    Case("somprompt/mark-text-bool", api(lambda t: __import__("somprompt").mark_text(True)), CLEAR,
         "number must be a whole number"),  # was: '1'
    Case("somprompt/mark-text-none", api(lambda t: __import__("somprompt").parse_mark_text(None)), CLEAR, "str"),
    Case("somprompt/parse-1mb", api(lambda t: _parse("the cup [3] " + "x" * 1_000_000, _LAB)), CORRECT,
         check=lambda o, t: o.value.ids == [3]),
    Case("somprompt/parse-unclosed-repeated-list", api(lambda t: _parse("The moved ones: " + "[3, " * 5000, _LAB)),
         CORRECT, check=lambda o, t: o.value.ids == [] and o.value.unknown == [],
         limit=5),  # was: 12 s (quadratic: every "[" rescanned the run; 100,000 items: hours)
    Case("somprompt/parse-unicode", api(lambda t: _parse("Der Becher [5] — 移动了 ✓", _LAB)), CORRECT,
         check=lambda o, t: o.value.ids == [5]),
    # ---- vlm_adapters
    Case("vlm/generate-none", api(lambda t: _stub_generate(None)), CLEAR, "frames must be"),
    Case("vlm/generate-string", api(lambda t: _stub_generate("video.mp4")), CLEAR, "frames must be"),
    Case("vlm/phrases-none", api(lambda t: _phrases(None)), CLEAR, "no answer"),
    Case("vlm/max-phrases-negative", api(lambda t: _phrases("a red cup, a blue box", max_phrases=-1)), CLEAR, "max_phrases"),
    Case("vlm/max-phrases-0", api(lambda t: _phrases("a red cup", max_phrases=0)), CLEAR, "max_phrases"),
    Case("vlm/frame-uint16-scaled", api(lambda t: _adapter_frame(np.dstack([_GRAD16] * 3))), CORRECT,
         check=lambda o, t: abs(float(o.value.mean()) - float(_GRAD16.mean()) / 257) < 1),
    Case("vlm/frame-float-nan", api(lambda t: _adapter_frame(np.full((8, 8, 3), np.nan))), CLEAR, "uint8"),
    Case("vlm/frame-float-out-of-range", api(lambda t: _adapter_frame(np.full((8, 8, 3), 7.0))), CLEAR, "uint8"),
    Case("vlm/frame-float-refused", api(lambda t: _adapter_frame(np.full((8, 8, 3), 0.5))), CLEAR, "np.clip"),
    Case("vlm/frame-0x0", api(lambda t: _adapter_frame(np.zeros((0, 0, 3), np.uint8))), CLEAR, "empty"),
    Case("vlm/frame-pil-16bit", api(lambda t: _adapter_frame(Image.fromarray(_GRAD16))), CORRECT,
         check=lambda o, t: o.value.shape == (64, 64, 3) and o.value.max() == round(_GRAD16.max() / 257)),
    Case("vlm/frame-pil-float-refused", api(lambda t: _adapter_frame(Image.fromarray(np.full((8, 8), 0.5, np.float32)))),
         CLEAR, "np.clip"),  # was: a black frame (PIL's convert("RGB") clips [0, 1] to 0)
    Case("vlm/frame-uint16-big-endian", api(lambda t: _adapter_frame(np.dstack([_GRAD16] * 3).astype(">u2"))), CORRECT,
         check=lambda o, t: abs(float(o.value.mean()) - float(_GRAD16.mean()) / 257) < 1),  # was: "got dtype >u2"
    Case("vlm/frame-pil-16bit-big-endian", api(lambda t: _adapter_frame(
        Image.frombytes("I;16B", (64, 64), _GRAD16.astype(">u2").tobytes()))), CORRECT,
         check=lambda o, t: o.value.max() == round(_GRAD16.max() / 257)),
    Case("vlm/frame-complex", api(lambda t: _adapter_frame(np.zeros((8, 8, 3), np.complex64))), CLEAR, "uint8"),
    Case("vlm/frame-int32", api(lambda t: _adapter_frame(np.zeros((8, 8, 3), np.int32))), CLEAR, "uint8"),
    Case("vlm/stub-cycle-str", api(lambda t: __import__("vlm_adapters").StubVLM(["a"], cycle="no")), CLEAR,
         "cycle must be True or False"),  # was: "no" read as True (answers started over)
    Case("vlm/stub-none", api(lambda t: __import__("vlm_adapters").StubVLM(None)), CLEAR,
         "responses must be"),  # was: "'NoneType' object is not iterable"
    Case("vlm/noun-phrases-none", api(lambda t: __import__("vlm_adapters").extract_noun_phrases(None)), CLEAR,
         "text must be a str"),  # was: "expected string or bytes-like object, got 'NoneType'"
    Case("vlm/phrases-control-characters", api(lambda t: _phrases("- red\x00cup: moved\n- blue\x1bbox: slid")), CORRECT,
         check=lambda o, t: o.value == ["red cup", "blue box"]),  # was: ['red\x00cup', 'blue\x1bbox'] sent to the detector
    Case("vlm/noun-phrases-non-ascii", api(lambda t: __import__("vlm_adapters").extract_noun_phrases(
        "The café cup moved and the Bécher fell.")), CORRECT,
         check=lambda o, t: o.value == ["café cup", "bécher"]),  # was: ['caf cup', 'b cher'] (letters beyond ASCII dropped)
    Case("vlm/noun-phrases-max-words-none", api(lambda t: __import__("vlm_adapters").extract_noun_phrases(
        "the red cup", max_words=None)), CLEAR, "max_words must be a whole number"),
    # was: TypeError "'<' not supported between instances of 'int' and 'NoneType'" (0 and -1: no phrase)
    Case("vlm/grounder-parse-returns-str", api(lambda t: __import__("vlm_adapters").TextGrounder(
        _NoDetector(), parse=lambda text: "cup").phrases("- a cup: moved")), CLEAR,
         "parse must return a list of str phrases"),  # was: ['c', 'u', 'p'] (a None or 3 in the list reached the detector)
    Case("somprompt/annotate-registry-int", api(lambda t: __import__("somprompt").MaskAnnotator().annotate(
        np.zeros((20, 20, 3), np.uint8), _LAB, 5)), CLEAR,
         "registry must be a somprompt.MarkRegistry"),  # was: "argument of type 'int' is not iterable"
    Case("somprompt/annotator-palette-int", api(lambda t: __import__("somprompt").MaskAnnotator(palette=5).annotate(
        np.zeros((20, 20, 3), np.uint8), _LAB)), CLEAR,
         "palette must be a somprompt.ColorPalette"),  # was: AttributeError "'int' object has no attribute 'by_number'"
    Case("vlm/checkpoint-none", api(lambda t: __import__("vlm_adapters").Qwen2_5_VLAdapter.from_pretrained(None)),
         CLEAR, "checkpoint folder"),  # was: "expected str, bytes or os.PathLike object, not NoneType"
    Case("vlm/checkpoint-empty", api(lambda t: __import__("vlm_adapters").Qwen2_5_VLAdapter.from_pretrained("")),
         CLEAR, "checkpoint folder"),  # was: '' passed on as a hub id
    Case("vlm/frames-empty", api(lambda t: _stub_generate([])), CLEAR, "empty"),
    Case("vlm/encode-max-side-0", api(lambda t: __import__("vlm_adapters.openai_compat").openai_compat.encode_image_data_url(
        Image.new("RGB", (64, 48)), max_side=0)), CLEAR, "max_side must be"),  # was: a 1x1 px image
    Case("vlm/encode-format-bogus", api(lambda t: __import__("vlm_adapters.openai_compat").openai_compat.encode_image_data_url(
        Image.new("RGB", (8, 8)), image_format="bogus")), CLEAR,
        "image_format must be 'png' or 'jpeg'"),  # was: KeyError 'BOGUS'
    Case("vlm/encode-numpy-array", api(lambda t: __import__("vlm_adapters.openai_compat").openai_compat.encode_image_data_url(
        _F[0])), CORRECT, check=lambda o, t: np.array_equal(_data_url_pixels(o.value), _F[0])),
    # was: "'numpy.ndarray' object has no attribute 'save'" (frames are arrays everywhere else)
    Case("vlm/openai-max-new-tokens-0", api(lambda t: _openai_generate(max_new_tokens=0)), CLEAR,
         "max_new_tokens must be >= 1"),  # was: sent "max_tokens": 0
    Case("vlm/openai-max-new-tokens-negative", api(lambda t: _openai_generate(max_new_tokens=-5)), CLEAR,
         "max_new_tokens must be >= 1"),  # was: sent "max_tokens": -5
    Case("vlm/openai-max-new-tokens-fraction", api(lambda t: _openai_generate(max_new_tokens=1.9)), CLEAR,
         "max_new_tokens must be a whole number"),  # was: sent "max_tokens": 1
    Case("vlm/openai-max-new-tokens-inf", api(lambda t: _openai_generate(max_new_tokens=float("inf"))), CLEAR,
         "max_new_tokens must be a whole number"),  # was: OverflowError "cannot convert float infinity to integer"
    Case("vlm/openai-prompt-none", api(lambda t: _openai_generate(None)), CLEAR,
         "prompt must be a str"),  # was: sent "text": null
    Case("vlm/openai-temperature-nan", api(lambda t: _openai_generate(do_sample=True, temperature=float("nan"))),
         CLEAR, "temperature must be a finite number >= 0"),  # was: sent "temperature": NaN (not JSON)
    Case("vlm/openai-temperature-negative", api(lambda t: _openai_generate(do_sample=True, temperature=-0.5)),
         CLEAR, "temperature must be a finite number >= 0"),  # was: sent "temperature": -0.5
    Case("vlm/openai-temperature-inf", api(lambda t: _openai_generate(do_sample=True, temperature=float("inf"))),
         CLEAR, "temperature must be a finite number >= 0"),  # was: sent "temperature": Infinity (not JSON)
    Case("vlm/openai-seed-fraction", api(lambda t: _openai_generate(seed=1.5)), CLEAR,
         "seed must be a whole number"),  # was: sent "seed": 1
    Case("vlm/sample-frames-str", api(lambda t: __import__("vlm_adapters").sample_frames("abc", 2)), CLEAR,
         "frames must be a list"),  # was: ['a', 'c'] (letters sampled as frames)
    Case("vlm/sample-frames-one-array", api(lambda t: __import__("vlm_adapters").sample_frames(_F[0], 2)), CORRECT,
         check=lambda o, t: len(o.value) == 1 and np.array_equal(o.value[0], _F[0])),  # was: rows 0 and 119 as two "frames"
    Case("vlm/generate-batch-none", api(lambda t: __import__("vlm_adapters").StubVLM("ok").generate_batch(
        None, "what moved?")), CLEAR, "videos must be a list of videos"),  # was: "object of type 'NoneType' has no len()"
    Case("vlm/generate-batch-prompts-none", api(lambda t: __import__("vlm_adapters").StubVLM("ok").generate_batch(
        [_F], None)), CLEAR, "prompts must be a str or a list"),  # was: "'NoneType' object is not iterable"
    Case("vlm/stub-prompt-none", api(lambda t: __import__("vlm_adapters").StubVLM("ok").generate(_F, None)), CLEAR,
         "prompt must be a str"),  # was: recorded and answered (the real adapters refuse it)
    Case("vlm/stub-max-new-tokens-0", api(lambda t: __import__("vlm_adapters").StubVLM("ok").generate(
        _F, "q", max_new_tokens=0)), CLEAR, "max_new_tokens must be >= 1"),  # was: answered
    Case("vlm/transformers-prompt-none", api(lambda t: _fake_transformers().generate(_F, None)), CLEAR,
         "prompt must be a str"),  # was: "prompts must be a str or a list of str" (a parameter not passed)
    Case("vlm/transformers-max-new-tokens-0", api(lambda t: _fake_transformers().generate(_F, "q", max_new_tokens=0)),
         CLEAR, "max_new_tokens must be >= 1"),  # was: handed to model.generate
    Case("vlm/transformers-fps-nan", api(lambda t: _fake_transformers(fps=float("nan"))), CLEAR,
         "fps must be"),  # was: NaN sent as the video's frame rate
    Case("vlm/internvideo-image-size-0", api(lambda t: __import__("vlm_adapters").InternVideo25Adapter(
        None, None, image_size=0)), CLEAR, "image_size must be >= 1"),  # was: failed in PIL's resize on the first frame
    Case("vlm/internvideo-image-size-fraction", api(lambda t: __import__("vlm_adapters").InternVideo25Adapter(
        None, None, image_size=447.5)), CLEAR, "image_size must be a whole number"),  # was: 447 px
    Case("vlm/internvideo-prompt-none", api(lambda t: __import__("vlm_adapters").InternVideo25Adapter(
        None, None).generate(_F, None)), CLEAR, "prompt must be a str"),  # was: "No module named 'torch'" / None sent
    Case("somprompt/to-hex-out-of-range", api(lambda t: __import__("somprompt").to_hex((300, 0, 0))), CLEAR,
         "must be three numbers in [0, 255]"),  # was: '#12c0000' ((-1, 0, 0): '#-10000')
    Case("somprompt/to-hex-fraction", api(lambda t: __import__("somprompt").to_hex((1.5, 0, 0))), CLEAR,
         "whole numbers"),  # was: "Unknown format code 'x' for object of type 'float'"
    Case("somprompt/contrast-ratio-none", api(lambda t: __import__("somprompt").contrast_ratio(None, (0, 0, 0))),
         CLEAR, "must be three numbers"),  # was: IndexError "too many indices for array"
    Case("somprompt/luminance-out-of-range", api(lambda t: __import__("somprompt").relative_luminance((300, 0, 0))),
         CLEAR, "must be three numbers in [0, 255]"),  # was: 0.31 (documented in [0, 1], for a colour that is none)
    Case("somprompt/distance-to-edge-3d", api(lambda t: __import__("somprompt").distance_to_edge(np.ones((4, 4, 3)))),
         CLEAR, "mask must be (H, W)"),  # was: OpenCV "src.type() == CV_8UC1" (1-D: an empty array)
    Case("somprompt/mask-anchor-nan", api(lambda t: __import__("somprompt").mask_anchor(
        np.where(np.eye(5) > 0, 1.0, np.nan))), CLEAR, "mask holds NaN"),  # was: NaN read as inside, (2, 2)
    Case("somprompt/distance-to-edge-nan", api(lambda t: __import__("somprompt").distance_to_edge(
        np.full((4, 4), np.nan))), CLEAR, "mask holds NaN"),  # was: all 0 (cast to uint8 0) and a RuntimeWarning
    Case("somprompt/distance-to-edge-256", api(lambda t: __import__("somprompt").distance_to_edge(
        np.full((3, 3), 256))), CORRECT, check=lambda o, t: o.value[1, 1] == 2 and o.value.min() == 1),
    # was: all 0 (256 cast to uint8 is 0: "outside"), while mask_anchor read it as inside
    Case("somprompt/mask-anchor-object-array", api(lambda t: __import__("somprompt").mask_anchor(
        np.array([[None, 1]]))), CLEAR, "mask must be a bool or numeric array"),
    # was: "int() argument must be a string, a bytes-like object or a real number, not 'NoneType'"
    Case("somprompt/regions-mask-fraction", api(lambda t: __import__("somprompt").LabelRegions(_LAB).mask(3.5)),
         CLEAR, "obj_id must be a whole number"),  # was: the mask of id 3 ("3" likewise)
    Case("somprompt/regions-largest-negative", api(lambda t: __import__("somprompt").LabelRegions(_LAB).largest(-1)),
         CLEAR, "n must be >= 0"),  # was: every object but the smallest kept (a slice [:-1])
    Case("somprompt/place-labels-size-negative", api(lambda t: __import__("somprompt").place_labels(
        __import__("somprompt").LabelRegions(_LAB), {3: (-4, 4), 5: (4, 4)})), CLEAR,
         "sizes[3] must be two whole numbers >= 1"),  # was: an inverted box (6, 2, 2, 6)
    Case("somprompt/place-labels-sizes-list", api(lambda t: __import__("somprompt").place_labels(
        __import__("somprompt").LabelRegions(_LAB), [(4, 4), (4, 4)])), CLEAR,
         "sizes must be a mapping"),  # was: {} (nothing placed)
    Case("somprompt/place-labels-gap-nan", api(lambda t: __import__("somprompt").place_labels(
        __import__("somprompt").LabelRegions(_LAB), {3: (4, 4)}, gap=float("nan"))), CLEAR,
         "gap must be a whole number"),  # was: read as no gap
    Case("somprompt/render-prefer-nan", api(lambda t: __import__("somprompt").SetOfMarkRenderer().render(
        np.zeros((20, 20, 3), np.uint8), _LAB, prefer={3: (np.nan, 1)})), CLEAR,
         "prefer[3] must be a whole number"),  # was: "cannot convert float NaN to integer"
    Case("somprompt/number-annotator-gap-nan", api(lambda t: __import__("somprompt").NumberAnnotator(gap=float("nan"))),
         CLEAR, "gap must be a whole number"),  # was: "cannot convert float NaN to integer"
    Case("somprompt/describe-marks-label-map", api(lambda t: __import__("somprompt").describe_marks(
        _LAB, __import__("somprompt").MarkRegistry())), CORRECT,
         check=lambda o, t: list(o.value) == [3, 5]),  # was: "'numpy.ndarray' object has no attribute 'ids'"
    Case("somprompt/describe-marks-frame-nan", api(lambda t: __import__("somprompt").describe_marks(
        __import__("somprompt").LabelRegions(_LAB), __import__("somprompt").MarkRegistry(), frame_index=float("nan"))),
         CLEAR, "frame_index must be a whole number"),  # was: "frame": NaN in the marks' JSON
    Case("somprompt/palette-by-number-0", api(lambda t: __import__("somprompt").ColorPalette.default().by_number(0)),
         CLEAR, "mark numbers start at 1"),  # was: the last colour (NaN: "cannot convert float NaN to integer")
    Case("somprompt/draw-registry-int", api(lambda t: __import__("somprompt").draw_marks(
        np.zeros((20, 20, 3), np.uint8), _LAB, registry=5)), CLEAR,
         "registry must be a somprompt.MarkRegistry"),  # was: "'int' object has no attribute 'register'"
    Case("somprompt/mark-video-renderer-int", api(lambda t: __import__("somprompt").mark_video(
        [np.zeros((20, 20, 3), np.uint8)], [_LAB], renderer=5)), CLEAR,
         "renderer must be a somprompt.SetOfMarkRenderer"),  # was: "'int' object has no attribute 'render'"
    Case("somprompt/mark-video-frames-none", api(lambda t: __import__("somprompt").mark_video(None, [_LAB])), CLEAR,
         "frames must be a list"),  # was: "'NoneType' object is not iterable"
    Case("somprompt/frames-for-vlm-none", api(lambda t: __import__("somprompt").frames_for_vlm(None)), CLEAR,
         "frames must be a list"),  # was: "'NoneType' object is not iterable"
    Case("somprompt/vqa-num-frames-0", api(lambda t: __import__("somprompt").GroundedVQA(
        lambda f: [_LAB], __import__("vlm_adapters").StubVLM("ok"), num_frames=0)), CLEAR,
         "num_frames must be >= 1"),  # was: refused by sample_for_vlm after segmenting
    Case("somprompt/vqa-max-side-0", api(lambda t: __import__("somprompt").GroundedVQA(
        lambda f: [_LAB], __import__("vlm_adapters").StubVLM("ok"), max_side=0)), CLEAR,
         "max_side must be >= 1"),  # was: refused after segmenting
    Case("somprompt/vqa-generation-int", api(lambda t: __import__("somprompt").GroundedVQA(
        lambda f: [_LAB], __import__("vlm_adapters").StubVLM("ok"), generation=5)), CLEAR,
         "generation must be a dict"),  # was: "'int' object is not iterable"
    # ---- the YOLOE path (answer -> phrases -> masks)
    Case("vlm/masks-to-labels-min-area-nan", api(lambda t: _masks_to_labels(min_area=float("nan"))), CLEAR,
         "min_area must be a whole number"),  # was: every instance kept (NaN compares false)
    Case("vlm/masks-to-labels-max-instances-negative", api(lambda t: _masks_to_labels(max_instances=-1)), CLEAR,
         "max_instances must be >= 1"),  # was: an empty label map
    Case("vlm/masks-to-labels-scores-nan", api(lambda t: _masks_to_labels(np.array([np.nan, 0.5]))), CLEAR,
         "scores must be finite"),  # was: the NaN mask painted last, whatever its score
    Case("vlm/masks-to-labels-mask-nan", api(lambda t: __import__("vlm_adapters").masks_to_label_map(
        np.full((1, 6, 6), np.nan))), CLEAR, "masks holds NaN"),  # was: every pixel labelled 1 (NaN is True)
    Case("vlm/masks-to-labels-scores-str", api(lambda t: _masks_to_labels(["high", "low"])), CLEAR,
         "scores must be numbers"),  # was: numpy's "could not convert string to float: 'high'"
    Case("vlm/detections-phrases-str", api(lambda t: __import__("vlm_adapters").Detections(
        np.stack([_M2[0]] * 3), [0.9, 0.8, 0.7], "cup")), CLEAR,
         "phrases must be a list of str"),  # was: three instances named 'c', 'u', 'p'
    Case("vlm/detections-phrases-none-item", api(lambda t: __import__("vlm_adapters").Detections(
        _M2, [0.9, 0.8], ["cup", None])), CLEAR, "got an item NoneType"),  # was: an instance named None
    Case("vlm/detections-scores-nan", api(lambda t: __import__("vlm_adapters").Detections(
        _M2, [np.nan, 0.8])), CLEAR, "scores must be confidences in [0, 1]"),  # was: refused only by masks_to_label_map
    Case("vlm/detections-scores-over-1", api(lambda t: __import__("vlm_adapters").Detections(
        _M2, [5, 0.8])), CLEAR, "scores must be confidences in [0, 1]"),  # was: accepted as a confidence of 5
    Case("vlm/detections-masks-nan", api(lambda t: __import__("vlm_adapters").Detections(
        np.full((1, 6, 6), np.nan), [0.5])), CLEAR, "masks holds NaN"),  # was: an all-True mask
    Case("vlm/yoloe-detect-phrases-str", api(lambda t: _yoloe().detect(np.zeros((8, 8, 3), np.uint8), "cup")),
         CLEAR, "phrases must be a list of str"),  # was: classes 'c', 'u', 'p' (here: "No module named 'torch'")
    Case("vlm/yoloe-detect-phrase-none", api(lambda t: _yoloe().detect(np.zeros((8, 8, 3), np.uint8), [None])),
         CLEAR, "got an item NoneType"),  # was: the class "None" (here: "No module named 'torch'")
    Case("vlm/yoloe-detect-blank-phrases", api(lambda t: _yoloe_sent(["", "cup", " ", "cup"])), CORRECT,
         check=lambda o, t: o.value == [["cup"]]),  # was: "" and " " sent to YOLOE as classes
    Case("vlm/yoloe-set-classes-str", api(lambda t: _yoloe().set_classes("cup", np.zeros((3, 4)))),
         CLEAR, "names must be a list of str"),  # was: 3 classes 'c', 'u', 'p' (here: "No module named 'torch'")
    Case("vlm/yoloe-conf-nan", api(lambda t: _yoloe(conf=float("nan"))), CLEAR,
         "conf must be a number in [0, 1]"),  # was: accepted, passed to predict on the first image
    Case("vlm/yoloe-max-det-fraction", api(lambda t: _yoloe(max_det=2.5)), CLEAR,
         "max_det must be a whole number"),  # was: accepted
    Case("vlm/yoloe-text-encoder-int", api(lambda t: _yoloe(text_encoder=5)), CLEAR,
         "text_encoder must be a file path"),  # was: "text encoder file '5' does not exist"
    Case("vlm/grounder-detector-none", api(lambda t: __import__("vlm_adapters").TextGrounder(None)), CLEAR,
         "detector must have detect"),  # was: AttributeError on the first answer
    Case("vlm/grounder-min-area-negative", api(lambda t: __import__("vlm_adapters").TextGrounder(
        _NoDetector(), min_area=-1)), CLEAR, "min_area must be >= 0"),  # was: accepted
    Case("vlm/method-vlm-none", api(lambda t: _method(vlm=None)), CLEAR,
         "vlm must have generate"),  # was: AttributeError on the first clip
    Case("vlm/method-prompt-none", api(lambda t: _method(prompt=None)), CLEAR,
         "prompt must be a non-empty str"),  # was: the stub was asked None
    Case("vlm/method-num-frames-0", api(lambda t: _method(num_frames=0)), CLEAR,
         "num_frames must be >= 1"),  # was: refused only on the first clip of the benchmark
    Case("vlm/method-generate-kwargs-int", api(lambda t: _method(generate_kwargs=5)), CLEAR,
         "generate_kwargs must be a dict"),  # was: "'int' object is not a mapping"
    Case("vlm/vlm-yoloe-conf-nan", api(lambda t: _vlm_yoloe(conf="nan")), CLEAR,
         "option 'conf' must be a number in [0, 1]"),  # was: accepted ('yoloe' file not found hid it)
    Case("vlm/vlm-yoloe-imgsz-0", api(lambda t: _vlm_yoloe(imgsz="0")), CLEAR, "option 'imgsz' must be >= 1"),
    Case("vlm/vlm-yoloe-max-new-tokens-0", api(lambda t: _vlm_yoloe(max_new_tokens="0")), CLEAR,
         "option 'max_new_tokens' must be >= 1"),  # was: accepted, sent to the VLM
    Case("vlm/vlm-yoloe-fps-negative", api(lambda t: _vlm_yoloe(fps="-1")), CLEAR, "option 'fps' must be a number > 0"),
    Case("vlm/vlm-yoloe-num-frames-bool", api(lambda t: _vlm_yoloe(num_frames=True)), CLEAR,
         "option 'num_frames' must be an integer"),  # was: True read as 1 frame
    Case("vlm/vlm-yoloe-yoloe-int", api(lambda t: _vlm_yoloe(yoloe=5)), CLEAR,
         "option 'yoloe' must be a file path"),  # was: "expected str, bytes or os.PathLike object, not int"
    # ---- demos (agent tool, web app, files)
    Case("demos/labels-zip-negative-ids", api(lambda t: _zip(t, [_LAB - 5], [0])), CLEAR,
         "negative ids"),  # was: ids -5.. wrapped to 65531.. in the 16-bit PNG
    Case("demos/labels-zip-ids-over-65535", api(lambda t: _zip(t, [_LAB * 100_000], [0])), CLEAR,
         "at most 65535"),  # was: 300000 wrapped to 37856
    Case("demos/labels-zip-more-maps-than-indices", api(lambda t: _zip(t, [_LAB, _LAB], [0])), CLEAR,
         "one index per map"),  # was: the second map dropped
    Case("demos/labels-zip-fractional-index", api(lambda t: _zip(t, [_LAB], [2.7])), CLEAR,
         "whole numbers"),  # was: written as 00002.png
    Case("demos/demo-clip-fractional-frames", api(lambda t: __import__("demos.media").media.write_demo_clip(
        t / "c.mp4", n_frames=2.5)), CLEAR, "n_frames must be a whole number"),
    # was: "'float' object cannot be interpreted as an integer"
    Case("demos/demo-clip-size-0", api(lambda t: __import__("demos.media").media.write_demo_clip(
        t / "c.mp4", n_frames=2, size=(0, 0))), CLEAR, "size must be"),  # was: OpenCV "inv_scale_x > 0"
    Case("demos/stub-answer-empty", api(lambda t: __import__("demos.vlm").vlm.stub_answer([])), CLEAR,
         "label_maps must be a non-empty list"),  # was: IndexError
    Case("demos/agent-arguments-dict", api(lambda t: __import__("demos.agent_example").agent_example._arguments(
        {"video": "clip.mp4", "n_nodes": 400})), CORRECT, check=lambda o, t: o.value == {"video": "clip.mp4", "n_nodes": 400}),
    # was: "the tool call's arguments are not valid JSON (the JSON object must be str, ... not dict)"
    Case("demos/answer-max-new-tokens-fraction", api(lambda t: __import__("demos.tool").tool.answer_question(
        _seg(), "what moved?", max_new_tokens=2.5)), CLEAR, "max_new_tokens must be a whole number"),  # was: 2
    Case("demos/answer-max-new-tokens-0", api(lambda t: __import__("demos.tool").tool.answer_question(
        _seg(), "what moved?", max_new_tokens=0)), CLEAR, "max_new_tokens must be >= 1"),  # was: sent to the VLM
    Case("demos/answer-question-empty", api(lambda t: __import__("demos.tool").tool.answer_question(_seg(), "")),
         CLEAR, "question must be a non-empty string"),  # was: answered ('' and 5 were asked)
    Case("demos/answer-seg-none", api(lambda t: __import__("demos.tool").tool.answer_question(None, "what moved?")),
         CLEAR, "seg must be a Segmentation"),  # was: AttributeError "'NoneType' ... no attribute 'label_maps'"
    Case("demos/describe-seg-none", api(lambda t: __import__("demos.tool").tool.describe_motionbits(None)),
         CLEAR, "seg must be a Segmentation"),  # was: AttributeError
    Case("demos/highlight-dim-nan", api(lambda t: __import__("demos.app").app.highlight(_seg(), [3], dim=float("nan"))),
         CLEAR, "dim must be a number in [0, 1]"),  # was: a black frame (2: uint8 wrapped)
    Case("demos/highlight-ids-fraction", api(lambda t: __import__("demos.app").app.highlight(_seg(), [3.5])),
         CLEAR, "whole numbers"),  # was: id 3 highlighted
    Case("demos/segment-window-config-dict", api(lambda t: __import__("demos.segmentation").segmentation.segment_window(
        t, config={"max_side": 100})), CLEAR, "config must be a MotionBitsConfig"),  # was: AttributeError 'with_'
    Case("demos/segment-window-progress-int", api(lambda t: __import__("demos.segmentation").segmentation.segment_window(
        t.parent / "assets" / "frames", progress=5)), CLEAR,
         "progress must be callable"),  # was: "'int' object is not callable" after the first frame
    Case("demos/limits-max-mb-nan", api(lambda t: __import__("demos.app").app.DemoLimits(max_mb=float("nan"))),
         CLEAR, "max_mb must be"),  # was: accepted, every upload passed the size check
    Case("demos/config-nodes-negative", api(lambda t: __import__("demos.app").app.DemoConfig(n_nodes=-5)),
         CLEAR, "n_nodes must be >= 16"),  # was: accepted (the page's slider default)
    Case("demos/config-max-new-tokens-0", api(lambda t: __import__("demos.app").app.DemoConfig(max_new_tokens=0)),
         CLEAR, "max_new_tokens must be >= 1"),  # was: accepted, sent with every question
    Case("demos/check-video-not-a-path", api(lambda t: __import__("demos.app").app.check_video(
        ["clip.mp4"], __import__("demos.app").app.DemoLimits())), CLEAR,
         "video must be the path"),  # was: "expected str, bytes or os.PathLike object, not list"
    Case("demos/check-video-limits-none", api(lambda t: __import__("demos.app").app.check_video(
        str(t.parent / "assets" / "clip.mp4"), None)), CLEAR,
         "limits must be a DemoLimits"),  # was: AttributeError "'NoneType' ... 'max_mb'"
    Case("demos/max-frames-for-nan", api(lambda t: __import__("demos.segmentation").segmentation.max_frames_for(
        float("nan"), 640)), CLEAR, "height must be a whole number"),  # was: 300
    Case("demos/app-step-bool", api(lambda t: __import__("demos.app").app._Handlers(
        __import__("demos.app").app.DemoConfig(), t).run(str(t.parent / "assets" / "clip.mp4"), 400, 0, 0, True)[-1]),
         CORRECT, check=lambda o, t: "Step must be a whole number" in o.value),  # was: True ran as step 1
]
# --------------------------------------------------------------------------- tests

@pytest.fixture
def tmp(tmp_path: Path, assets: Path) -> Path:
    """A fresh folder per case, next to the assets (``{a}`` = ../assets)."""
    link = tmp_path.parent / "assets"
    if not link.exists():
        link.symlink_to(assets)
    return tmp_path


def _leftovers(tmp: Path) -> list[str]:
    return [str(p.relative_to(tmp)) for p in tmp.rglob("*") if ".partial-" in p.name]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_case(case: Case, tmp: Path) -> None:
    reason = case.requires() if case.requires is not None else None
    if reason:
        pytest.skip(reason)
    got, why, o = run_case(case, tmp)
    assert got == case.expect, f"{case.id}: {got}: {why}"
    assert not _leftovers(tmp), f"partial output left: {_leftovers(tmp)}"
    for rel in case.absent:
        assert not (tmp / rel).exists(), f"{rel} was written although the command failed"
    if case.id in ("segment/rerun-refused", "segment/failed-rerun-keeps-old"):
        assert labels_in(tmp / "out") == [f"{i:05d}.png" for i in range(6)]  # untouched


def test_debug_shows_the_traceback(tmp: Path) -> None:
    from motionbits.cli import main

    with pytest.raises(FileNotFoundError):
        main(["segment", str(tmp / "nope.mp4"), "--debug"])
    with pytest.raises(FileNotFoundError):
        main(["--debug", "segment", str(tmp / "nope.mp4")])


def test_sparse_matching_equals_dense() -> None:
    """The sparse path finds a matching of the same total score as the dense one."""
    from motionbits.eval import matching

    rng = np.random.default_rng(0)
    for trial in range(40):
        k, m = rng.integers(1, 25, 2)
        n = int(rng.integers(1, k * m + 1))
        idx = rng.choice(k * m, n, replace=False)
        r, c = np.divmod(idx, m)
        s = rng.random(n) + 0.01 if trial % 2 else np.round(rng.random(n), 1) + 0.1
        dense = np.zeros((k, m))
        dense[r, c] = s
        best = dense[matching.hungarian_match(dense)].sum()
        with mock.patch.object(matching, "DENSE_MATCH_CELLS", 0):
            rows, cols = matching.sparse_hungarian_match(k, m, r, c, s)
        assert len(set(rows)) == len(rows) and len(set(cols)) == len(cols)
        assert np.isclose(dense[rows, cols].sum(), best)
        rows, cols = matching._augmented_match(k, m, r, c, s)
        assert np.isclose(dense[rows, cols].sum(), best)


def report(cases: list[Case] = CASES, isolate: bool = False) -> dict[str, int]:
    """Run every case and print its verdict and the counts (``python tests/test_bad_inputs.py``).

    ``isolate``: each case in its own process, killed after its time limit (a hang in
    native code cannot be interrupted from Python).
    """
    import subprocess
    import tempfile

    counts = dict.fromkeys(VERDICTS, 0)
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        build_assets(root / "assets")
        for i, case in enumerate(cases):
            tmp = root / f"case{i}"
            tmp.mkdir()
            if isolate:
                try:
                    p = subprocess.run([sys.executable, __file__, "--one", case.id, str(tmp)],
                                       capture_output=True, text=True, timeout=case.limit + 30)
                    got, _, why = p.stdout.strip().splitlines()[-1].partition("\t")
                    if got not in VERDICTS:
                        got, why = TRACEBACK, p.stderr[-300:]
                except subprocess.TimeoutExpired:
                    got, why = HANG, f"killed after {case.limit + 30:g} s"
                except IndexError:
                    got, why = TRACEBACK, p.stderr[-300:]
            else:
                got, why = _judge(case, tmp)
            counts[got] += 1
            print(f"{case.id:<44} {got:<15} {'' if got == case.expect else why[:150]}", flush=True)
    print(f"{len(cases)} cases: " + ", ".join(f"{v} {n}" for v, n in counts.items()))
    return counts


def _judge(case: Case, tmp: Path) -> tuple[str, str]:
    got, why, _ = run_case(case, tmp)
    left = _leftovers(tmp) + [rel for rel in case.absent if (tmp / rel).exists()]
    if got == case.expect and left:
        return WRONG, f"partial or stale output left: {left}"
    return got, why


if __name__ == "__main__":  # python tests/test_bad_inputs.py [--isolate] [--skip CASE_ID ...]
    if "--one" in sys.argv:  # internal: one case in this process, for --isolate
        case_id, tmp_dir = sys.argv[sys.argv.index("--one") + 1:][:2]
        got, why = _judge(next(c for c in CASES if c.id == case_id), Path(tmp_dir))
        print(f"{got}\t{' '.join(why.split())}")
        sys.exit(0)
    skip = set(sys.argv[sys.argv.index("--skip") + 1:]) if "--skip" in sys.argv else set()
    report([c for c in CASES if c.id not in skip], isolate="--isolate" in sys.argv)
