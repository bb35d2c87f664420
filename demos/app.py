"""``motionbits-demo``: a Gradio web app over the MotionBits toolkit.

Upload a video (or pick an example), choose the graph nodes, the time window and the
frame step, and run: the page shows the overlay video with numbered marks (H.264), a table
of MotionBits, and offers the label maps (zip) and ``summary.json``. Then ask a question:
the VLM (the stub unless ``--vlm`` names a model folder or an endpoint) answers with
Set-of-Mark citations, and the cited masks are highlighted on the last frame.

Every handler turns bad input into a one-line message in the page (``#status``), never a
stack trace.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import numbers
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from motionbits.frames import whole_number
from motionbits.video_writer import write_h264
from somprompt import draw_marks, mark_video
from somprompt.registry import whole_ids

from .media import write_demo_clip, write_labels_zip
from .segmentation import (MAX_VIDEO_SIDE, Segmentation, check_segmentation, check_window, max_frames_for,
                           segment_window)
from .tool import answer_question, describe_motionbits
from .vlm import VLMError, make_vlm, vlm_spec_help

__all__ = ["DemoConfig", "DemoLimits", "build_app", "check_video", "highlight", "main"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class DemoLimits:
    """What the app accepts (stated in the page).

    Attributes:
        max_mb: largest upload, MB.
        max_side: longest side of the video, pixels (the tools' ``MAX_VIDEO_SIDE`` at most).
        max_frames: most frames processed in one run (after start / frames / step).
    """

    max_mb: float = 100.0
    max_side: int = MAX_VIDEO_SIDE
    max_frames: int = 300

    def __post_init__(self) -> None:  # else a NaN max_mb let every upload through
        if (isinstance(self.max_mb, bool) or not isinstance(self.max_mb, numbers.Real)
                or not (math.isfinite(self.max_mb) and self.max_mb > 0)):
            raise ValueError(f"max_mb must be a finite number > 0, got {self.max_mb!r}")
        if not 1 <= whole_number("max_side", self.max_side) <= MAX_VIDEO_SIDE:
            raise ValueError(f"max_side must be in [1, {MAX_VIDEO_SIDE}], got {self.max_side!r}")
        if whole_number("max_frames", self.max_frames) < 2:
            raise ValueError(f"max_frames must be >= 2, got {self.max_frames!r}")

    def text(self) -> str:
        return (f"video files up to {self.max_mb:g} MB, at most {self.max_side} px on the longer "
                f"side, at least 2 frames; at most {self.max_frames} frames processed per run "
                f"(fewer for large frames: {max_frames_for(1080, 1920)} at 1920x1080)")


@dataclass(frozen=True)
class DemoConfig:
    """Settings of the app.

    Attributes:
        vlm: VLM spec (:func:`demos.vlm.make_vlm`); default the scripted stub.
        limits: input limits.
        n_nodes: default of the nodes slider.
        max_new_tokens: longest answer in tokens (None: the VLM adapter's default).
        workdir: folder for generated files (default: a new temporary folder).
        examples: extra example videos (the generated clip is always offered).
    """

    vlm: str = "stub"
    limits: DemoLimits = field(default_factory=DemoLimits)
    n_nodes: int = 2500
    max_new_tokens: int | None = None
    workdir: str | None = None
    examples: tuple[str, ...] = ()

    def __post_init__(self) -> None:  # checked before the page is built, not on the first run
        check_window(n_nodes=self.n_nodes)
        if self.max_new_tokens is not None and whole_number("max_new_tokens", self.max_new_tokens) < 1:
            raise ValueError(f"max_new_tokens must be >= 1 or None, got {self.max_new_tokens!r}")
        if not isinstance(self.limits, DemoLimits):
            raise TypeError(f"limits must be a DemoLimits, got {type(self.limits).__name__}")


def check_video(path: str | None, limits: DemoLimits) -> tuple[int, tuple[int, int], float]:
    """Check an uploaded file against ``limits``; returns (frame count, (H, W), fps).

    Raises:
        ValueError: no file, a missing file, not a video, fewer than 2 frames, or over a limit
            (one line).
        TypeError: ``limits`` is not a :class:`DemoLimits`.
    """
    if not isinstance(limits, DemoLimits):  # else "'NoneType' object has no attribute 'max_mb'"
        raise TypeError(f"limits must be a DemoLimits, got {type(limits).__name__} {limits!r:.40}")
    if not path:
        raise ValueError("no video: upload a video file or pick an example")
    if not isinstance(path, (str, os.PathLike)):  # else os.fspath's "expected str, bytes or os.PathLike"
        raise ValueError(f"video must be the path of a video file, got {type(path).__name__} {path!r:.40}")
    p = Path(path)
    if not p.exists():
        raise ValueError(f"video not found: {p} (upload it again)")
    size_mb = p.stat().st_size / 1e6
    if size_mb > limits.max_mb:
        raise ValueError(f"{p.name} is {size_mb:.0f} MB, over the limit of {limits.max_mb:g} MB")
    cap = cv2.VideoCapture(str(p))
    try:
        ok, frame = cap.read() if cap.isOpened() else (False, None)
        if not ok:
            raise ValueError(f"{p.name} is not a video this app can read (no decodable frame)")
        h, w = frame.shape[:2]
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        if n <= 0:  # unknown count: count by decoding
            n = 1
            while cap.grab():
                n += 1
        fps = float(cap.get(cv2.CAP_PROP_FPS)) or 10.0
    finally:
        cap.release()
    if n < 2:
        raise ValueError(f"{p.name} has {n} frame; MotionBits needs at least 2 frames to see motion")
    if max(h, w) > limits.max_side:
        raise ValueError(f"{p.name} is {w}x{h}, over the limit of {limits.max_side} px on the longer side")
    return n, (h, w), fps


def _window(n: int, size: tuple[int, int], start: int, frames: int, every: int, limits: DemoLimits) -> int:
    """Frames the run will process; raises ValueError for a window outside the video or over the limits."""
    if start >= n:
        raise ValueError(f"start frame {start} is past the end of the video ({n} frames)")
    count = (n - 1 - start) // every + 1
    if frames:
        count = min(count, frames)
    if count < 2:
        raise ValueError(f"the window holds {count} frame (start {start}, step {every}); need at least 2")
    most = min(limits.max_frames, max_frames_for(*size))
    if count > most:
        raise ValueError(f"the window holds {count} frames, over the limit of {most} at "
                         f"{size[1]}x{size[0]}: set Frames or a larger Step")
    return count


def _whole(label: str, value: object, default: int | None = None) -> int:
    """A page field as a whole number (None: ``default``); ValueError naming the field."""
    if value is None and default is not None:
        return default
    if isinstance(value, bool):  # else True read as 1
        raise ValueError(f"{label} must be a whole number, got {value!r}")
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        number = float("nan")
    if not number.is_integer():  # 'abc', None, nan, inf, 2.5
        raise ValueError(f"{label} must be a whole number, got {value!r}")
    return int(number)


def _ranges(frames: list[int]) -> str:
    """[1, 2, 3, 7] -> '1-3, 7'."""
    out, run = [], []
    for f in frames:
        if run and f != run[-1] + 1:
            out.append(run)
            run = []
        run.append(f)
    if run:
        out.append(run)
    return ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 1 else f"{r[0]}" for r in out) or "-"


def highlight(seg: Segmentation, ids: list[int], dim: float = 0.35) -> np.ndarray:
    """The last frame with the MotionBits ``ids`` marked and everything else dimmed.

    Returns (H, W, 3) uint8 RGB; the marks use the numbers and colours of the overlay.
    ``dim``: brightness kept outside the marks, in [0, 1].
    """
    check_segmentation(seg)
    ids = whole_ids(ids, "ids", "MotionBit ids")  # else [1.5] marked id 1
    if (isinstance(dim, bool) or not isinstance(dim, numbers.Real)
            or not (math.isfinite(dim) and 0 <= dim <= 1)):  # else NaN: black; 2: uint8 wrapped
        raise ValueError(f"dim must be a number in [0, 1], got {dim!r}")
    frame, labels = seg.frames[-1], seg.label_maps[-1]
    keep = np.isin(labels, np.asarray(ids, dtype=np.int64)) if len(ids) else np.zeros(labels.shape, bool)
    marked = draw_marks(frame, np.where(keep, labels, 0), registry=seg.registry)
    out = (frame.astype(np.float32) * dim).astype(np.uint8)
    # marks (numbers, outlines) may extend past the masks: keep every pixel they changed
    changed = keep | np.any(marked != frame, axis=2)
    out[changed] = marked[changed]
    return out


def _table(records: list[dict]) -> list[list]:
    return [[r["mark"], r["id"], r["area"], _ranges(r["moved_frames"])] for r in records]


class _Handlers:
    """The app's callbacks; each returns a status line instead of raising."""

    def __init__(self, config: DemoConfig, workdir: Path):
        self.config = config
        self.workdir = workdir
        self._vlm: Any = None

    def run(self, path, n_nodes, start, frames, every, progress=None):
        """Segment; returns (overlay mp4, table rows, labels.zip, summary.json, state, status)."""
        empty = (None, [], None, None, None)  # overlay, table, zip, summary, state
        try:
            start, frames = _whole("Start frame", start, 0), _whole("Frames", frames, 0)
            every, n_nodes = _whole("Step", every, 1), _whole("Graph nodes", n_nodes)
            if start < 0 or frames < 0 or every < 1:
                raise ValueError(f"start ({start}) and frames ({frames}) must be >= 0 and step ({every}) >= 1")
            n, size, fps = check_video(path, self.config.limits)
            count = _window(n, size, start, frames, every, self.config.limits)
            bar = progress if progress is not None else (lambda *a, **k: None)
            bar((0, count), desc="segmenting", unit="frames")
            seg = segment_window(path, start=start, frames=count, every=every, n_nodes=n_nodes,
                                 progress=lambda done, total: bar((done, count), desc="segmenting",
                                                                  unit="frames"))
            out = Path(tempfile.mkdtemp(dir=self.workdir))
            marked = mark_video(seg.frames, seg.label_maps)
            video = write_h264(list(marked.frames), out / "overlay.mp4", fps=max(fps / every, 1.0))
            records = describe_motionbits(seg)
            summary = {
                "input": Path(path).name, "frame_indices": seg.frame_indices,
                "size": list(seg.label_maps[-1].shape), "seconds": round(seg.seconds, 3),
                "config": dataclasses.asdict(seg.config), "every": every, "motionbits": records,
            }
            (out / "summary.json").write_text(json.dumps(summary, indent=1))
            zip_path = write_labels_zip(seg.label_maps, seg.frame_indices, out / "labels.zip")
            status = (f"{len(records)} MotionBits in the last frame; {len(seg.frames)} frames "
                      f"segmented in {seg.seconds:.1f} s.")
            return (str(video), _table(records), str(zip_path), str(out / "summary.json"),
                    seg, status)
        except (ValueError, FileNotFoundError, TypeError) as exc:
            return (*empty, f"**Error:** {exc}")
        except Exception as exc:  # never a stack trace in the page
            log.exception("run failed")
            return (*empty, f"**Error:** {type(exc).__name__}: {' '.join(str(exc).split())}")

    def ask(self, seg: Segmentation | None, question: str):
        """Answer; returns (answer text, highlight image or None, "Highlighted: ..." or an error)."""
        try:
            if seg is None:
                raise ValueError("run the segmentation first, then ask")
            if question is not None and not isinstance(question, str):
                raise ValueError(f"the question must be text, got {type(question).__name__} {question!r:.40}")
            if not question or not question.strip():
                raise ValueError("type a question first")
            vlm = None if self.config.vlm == "stub" else self._load_vlm()
            ans = answer_question(seg, question.strip(), vlm, max_new_tokens=self.config.max_new_tokens)
            registry = seg.registry
            cited = ", ".join(f"[{registry.text(i)}] (id {i})" for i in ans.cited_ids) or "none"
            return ans.answer, highlight(seg, ans.cited_ids), f"Highlighted: {cited}."
        except (ValueError, VLMError) as exc:
            return "", None, f"**Error:** {exc}"
        except Exception as exc:  # never a stack trace in the page
            log.exception("ask failed")
            return "", None, f"**Error:** {type(exc).__name__}: {' '.join(str(exc).split())}"

    def _load_vlm(self):
        if self._vlm is None:
            self._vlm = make_vlm(self.config.vlm)
        return self._vlm


def build_app(config: DemoConfig | None = None):
    """The Gradio ``Blocks`` of the demo (not launched)."""
    import gradio as gr

    config = config or DemoConfig()
    workdir = Path(config.workdir or tempfile.mkdtemp(prefix="motionbits-demo-"))
    workdir.mkdir(parents=True, exist_ok=True)
    clip = workdir / "generated_clip.mp4"
    if not clip.exists():
        write_demo_clip(clip)
    examples = [[str(clip)]] + [[e] for e in config.examples]
    h = _Handlers(config, workdir)
    vlm_text = "the scripted stub (it does not look at the video)" if config.vlm == "stub" else f"`{config.vlm}`"

    with gr.Blocks(title="MotionBits demo") as app:
        gr.Markdown(
            "# MotionBits: moving rigid bodies, by their motion alone\n"
            "Upload a video or pick an example, run, then ask a question about what moved. "
            f"Limits: {config.limits.text()}. VLM: {vlm_text}.")
        seg_state = gr.State(None)
        with gr.Row():
            with gr.Column():
                video_in = gr.File(label="Video", type="filepath", elem_id="video-in")
                gr.Examples(examples, inputs=[video_in], label="Examples")
                nodes = gr.Slider(100, 10000, value=config.n_nodes, step=100, label="Graph nodes",
                                  elem_id="nodes")
                with gr.Row():
                    start = gr.Number(0, label="Start frame", precision=0, minimum=0, elem_id="start")
                    frames = gr.Number(0, label="Frames (0 = all)", precision=0, minimum=0, elem_id="frames")
                    every = gr.Number(1, label="Step", precision=0, minimum=1, elem_id="every")
                run_btn = gr.Button("Segment", variant="primary", elem_id="run")
                status = gr.Markdown("", elem_id="status")
            with gr.Column():
                overlay = gr.Video(label="MotionBits (numbered marks)", elem_id="overlay",
                                   interactive=False)
                table = gr.Dataframe(headers=["mark", "id", "area (px)", "moved in frames"],
                                     label="MotionBits in the last frame", elem_id="table",
                                     interactive=False)
                with gr.Row():
                    labels_zip = gr.File(label="labels.zip", elem_id="labels-zip")
                    summary = gr.File(label="summary.json", elem_id="summary")
        with gr.Row():
            with gr.Column():
                question = gr.Textbox(label="Question", placeholder="Which objects moved together?",
                                      elem_id="question")
                ask_btn = gr.Button("Ask", elem_id="ask")
                answer = gr.Textbox(label="Answer", interactive=False, elem_id="answer")
                cited = gr.Markdown("", elem_id="cited")
            with gr.Column():
                shown = gr.Image(label="Cited MotionBits on the last frame", type="numpy",
                                 interactive=False, elem_id="highlight")

        def run(path, n, s, f, e, progress=gr.Progress()):
            return h.run(path, n, s, f, e, progress=progress)

        run_btn.click(run, [video_in, nodes, start, frames, every],
                      [overlay, table, labels_zip, summary, seg_state, status])
        ask_btn.click(h.ask, [seg_state, question], [answer, shown, cited])
        question.submit(h.ask, [seg_state, question], [answer, shown, cited])
    return app


def _examples_in_checkout() -> tuple[str, ...]:
    """Short real clips shipped in the repository's ``examples/`` folder, if present."""
    folder = Path(__file__).resolve().parents[1] / "examples"
    return tuple(str(p) for p in sorted(folder.glob("*.mp4"))) if folder.is_dir() else ()


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``motionbits-demo``."""
    parser = argparse.ArgumentParser(prog="motionbits-demo", description="MotionBits web demo (Gradio).")
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on (default: %(default)s)")
    parser.add_argument("--port", type=int, default=7860, help="port (default: %(default)s)")
    parser.add_argument("--vlm", default="stub", help=f"VLM for questions: {vlm_spec_help()}")
    parser.add_argument("--nodes", type=int, default=DemoConfig.n_nodes,
                        help="default graph nodes (default: %(default)s)")
    parser.add_argument("--max-new-tokens", type=int, default=None,
                        help="longest answer in tokens (default: the VLM adapter's)")
    args = parser.parse_args(argv)
    os.environ.setdefault("GRADIO_ANALYTICS_ENABLED", "False")
    try:  # --nodes 5 or --max-new-tokens 0: refused before a page is built
        DemoConfig(n_nodes=args.nodes, max_new_tokens=args.max_new_tokens)
    except ValueError as exc:
        parser.error(str(exc).replace("n_nodes", "--nodes").replace("max_new_tokens", "--max-new-tokens"))
    config = DemoConfig(vlm=args.vlm, n_nodes=args.nodes, max_new_tokens=args.max_new_tokens,
                        workdir=tempfile.mkdtemp(prefix="motionbits-demo-"), examples=_examples_in_checkout())
    app = build_app(config)
    allowed = [config.workdir, *{str(Path(e).parent) for e in config.examples}]  # files the app may serve
    app.queue().launch(server_name=args.host, server_port=args.port, allowed_paths=allowed, show_error=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
