"""MotionBits as a tool for agents: JSON in, JSON out.

``segment_moving_bodies`` returns, for each MotionBit of the last frame, what a planner
needs (mask as COCO RLE, box, centroid, principal axes, twist, the frames it moved in and
a top-down grasp); ``ask_about_motion`` answers a question about the video with a VLM and
Set-of-Mark prompts (GroundedVQA), naming the cited MotionBits. Every value returned is
JSON-serialisable (str, int, float, list, dict).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from motionbits import MotionBitsConfig, grasp_from_mask, instance_from_mask
from motionbits.frames import whole_number
from somprompt import GroundedVQA, draw_marks
from somprompt.registry import whole_ids

from .segmentation import Segmentation, check_segmentation, segment_window
from .vlm import VLMError, make_vlm, stub_answer

__all__ = ["Answer", "answer_question", "ask_about_motion", "cited_records", "describe_motionbits",
           "segment_moving_bodies"]


def describe_motionbits(seg: Segmentation) -> list[dict[str, Any]]:
    """One JSON record per MotionBit in the last frame of ``seg``, largest first.

    Keys: ``id``; ``mark`` (its number on the marked frames); ``area`` (px); ``box``
    [x0, y0, x1, y1] (exclusive end); ``centroid`` [x, y]; ``principal_axes``
    (``major``/``minor`` unit [x, y] vectors and the mask's ``major_length``/
    ``minor_length`` along them, px); ``twist`` {``omega`` rad/step, ``vx``, ``vy``
    px/step} at its latest motion (step = ``every`` frames; about the image origin;
    zeros if it never moved); ``moved_frames`` (video frame indices); ``mask`` (COCO
    RLE); ``grasp`` {``center`` [x, y], ``angle`` rad of the closing direction from +x
    towards +y, ``width`` px opening} as in the paper's tower-stacking controller.
    """
    labels = check_segmentation(seg).label_maps[-1]
    registry = seg.registry
    records = []
    for i in seg.last_ids:
        mask = labels == i
        obj = instance_from_mask(mask, i, rle=True)  # box, area, centroid, COCO RLE
        g = grasp_from_mask(mask)
        tw = seg.twists.get(i, (0.0, 0.0, 0.0))
        records.append({
            "id": i,
            "mark": registry.number(i),
            "area": obj.area,
            "box": list(obj.bbox),
            "centroid": [round(c, 2) for c in obj.centroid],
            "principal_axes": {"major": [round(v, 4) for v in g.major_axis],
                               "minor": [round(v, 4) for v in g.minor_axis],
                               "major_length": round(g.length, 2),
                               "minor_length": round(g.width, 2)},
            "twist": {"omega": float(tw[0]), "vx": float(tw[1]), "vy": float(tw[2])},
            "moved_frames": list(seg.moved.get(i, [])),
            "mask": obj.rle,
            "grasp": {"center": [round(c, 2) for c in g.centroid],
                      "angle": round(g.angle, 4), "width": round(g.width, 2)},
        })
    records.sort(key=lambda r: (-r["area"], r["id"]))
    return records


def _marked_path(path: object) -> Path:
    """``marked_image`` checked before any work: a .png/.jpg path in an existing folder."""
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path).strip():
        raise ValueError(f"marked_image must be a .png or .jpg path, got {path!r}")
    out = Path(os.path.expanduser(os.fspath(path)))
    if out.suffix.lower() not in (".png", ".jpg", ".jpeg"):
        raise ValueError(f"marked_image must end in .png or .jpg, got {str(out)!r}")
    if not out.parent.is_dir():
        raise FileNotFoundError(f"folder of marked_image does not exist: {out.parent}")
    return out


def _write_marked(seg: Segmentation, out: Path) -> str:
    try:
        Image.fromarray(draw_marks(seg.frames[-1], seg.label_maps[-1], registry=seg.registry)).save(out)
    except OSError as exc:  # a folder of that name, no permission, a full disk
        raise ValueError(f"could not write marked_image {out}: {exc.strerror or exc}; "
                         "give a writable .png or .jpg path") from exc
    return str(out)


def segment_moving_bodies(video: "str | os.PathLike", *, start: int = 0, frames: int | None = None,
                          every: int = 1, n_nodes: int = MotionBitsConfig.n_nodes,
                          marked_image: "str | os.PathLike | None" = None) -> dict[str, Any]:
    """Segment the moving rigid bodies of a video and describe each for an agent.

    Args:
        video: path of a video file or of a folder of images, at most ``MAX_VIDEO_SIDE``
            (1920) px on the longer side.
        start: first frame used (0-based).
        frames: number of frames used (>= 2; None: to the end of the video).
        every: use every ``every``-th frame.
        n_nodes: graph nodes (more: finer masks, slower; at most ``MAX_NODES``, 40,000).
        marked_image: if given, a .png/.jpg path where the last frame is written with the
            numbered marks (to show a VLM); returned as ``marked_image``.

    Returns:
        ``{"video", "frame_indices", "size": [H, W], "n_nodes", "seconds", "motionbits":
        [...]}`` with the records of :func:`describe_motionbits` (MotionBits of the last
        frame, largest first), plus ``marked_image`` when asked for.

    Raises:
        FileNotFoundError: the video (or the folder of ``marked_image``) does not exist.
        ValueError: a bad argument, an unreadable / too short video, frames too large or
            too thin, or a ``marked_image`` that cannot be written.
    """
    marked = None if marked_image is None else _marked_path(marked_image)
    seg = segment_window(video, start=start, frames=frames, every=every, n_nodes=n_nodes)
    out: dict[str, Any] = {
        "video": seg.video,
        "frame_indices": seg.frame_indices,
        "size": [int(s) for s in seg.label_maps[-1].shape],
        "n_nodes": seg.config.n_nodes,
        "seconds": round(seg.seconds, 3),
        "motionbits": describe_motionbits(seg),
    }
    if marked is not None:
        out["marked_image"] = _write_marked(seg, marked)
    return out


def ask_about_motion(video: "str | os.PathLike", question: str, *, vlm: "str | Any | None" = None,
                     start: int = 0, frames: int | None = None, every: int = 1,
                     n_nodes: int = MotionBitsConfig.n_nodes) -> dict[str, Any]:
    """Answer a question about a video with a VLM shown the MotionBits as numbered marks.

    Args:
        video, start, frames, every, n_nodes: as in :func:`segment_moving_bodies`.
        question: the question (non-empty).
        vlm: a VLM spec for :func:`demos.vlm.make_vlm` (``"stub"``, ``"stub:TEXT"``, a
            local model folder, ``"openai:URL@MODEL"``, ...), an object with
            ``generate(frames, prompt, system=None)``, or None: the stub, which does not
            look at the video and cites the largest MotionBit of the last frame.

    Returns:
        ``{"question", "answer", "cited": [{"mark", "id", "area", "box"}], "vlm"}``.

    Raises:
        FileNotFoundError: the video does not exist.
        ValueError: an empty question, a bad argument or an unreadable / too short video.
        VLMError: an unusable VLM spec, or the VLM failed or answered no text.
    """
    _check_question(question)
    seg = segment_window(video, start=start, frames=frames, every=every, n_nodes=n_nodes)
    result = answer_question(seg, question, vlm)
    return {"question": question, "answer": result.answer, "vlm": _vlm_name(result.vlm),
            "cited": cited_records(seg, result.cited_ids)}


def _check_question(question: object) -> None:
    if not isinstance(question, str) or not question.strip():
        raise ValueError("question must be a non-empty string")


@dataclass
class Answer:
    """A VLM's answer on a segmented window.

    Attributes:
        answer: the VLM's text.
        cited_ids: MotionBit ids cited in it, in order of first mention.
        masks: cited id -> (H, W) bool mask on the last frame.
        vlm: the VLM that answered.
    """

    answer: str
    cited_ids: list[int]
    masks: dict[int, np.ndarray]
    vlm: Any


def answer_question(seg: Segmentation, question: str, vlm: "str | Any | None" = None, *,
                    max_new_tokens: int | None = None) -> Answer:
    """GroundedVQA on an already segmented window (``seg``'s label maps, no second run).

    ``vlm`` as in :func:`ask_about_motion`; ``max_new_tokens`` caps the answer (None: the
    VLM's default, else a whole number >= 1). Raises VLMError when the VLM cannot be built,
    fails or answers no text; TypeError / ValueError for a ``seg`` that is not a
    :class:`Segmentation`, an empty question or a bad ``max_new_tokens``.
    """
    check_segmentation(seg)
    _check_question(question)
    if max_new_tokens is not None and whole_number("max_new_tokens", max_new_tokens) < 1:
        raise ValueError(f"max_new_tokens must be >= 1 or None, got {max_new_tokens!r}")
    if vlm is None or isinstance(vlm, str):
        vlm = make_vlm(vlm or "stub", stub_text=stub_answer(seg.label_maps))
    elif not callable(getattr(vlm, "generate", None)):
        raise TypeError(f"vlm must be a VLM spec or have generate(frames, prompt, system=None), "
                        f"got {type(vlm).__name__}")
    generation = {} if max_new_tokens is None else {"max_new_tokens": int(max_new_tokens)}
    res = GroundedVQA(lambda frames: seg.label_maps, _Failing(vlm), generation=generation)(
        seg.frames, question=question)
    return Answer(res.answer, res.cited_ids, res.masks, vlm)


class _Failing:
    """``vlm`` whose every failure is a VLMError: an exception in ``generate`` (endpoint
    down, model or processor error) or an answer that is not text (None, a dict)."""

    def __init__(self, vlm: Any):
        self.vlm = vlm

    def generate(self, frames: list, prompt: str, system: str | None = None, **gen: Any) -> str:
        try:
            answer = self.vlm.generate(frames, prompt, system=system, **gen)
        except Exception as exc:
            raise VLMError(f"the VLM did not answer: {' '.join(str(exc).split()) or type(exc).__name__}") from exc
        if not isinstance(answer, str):
            raise VLMError(f"the VLM did not answer: it returned {type(answer).__name__}, not text")
        return answer


def cited_records(seg: Segmentation, ids: list[int]) -> list[dict[str, Any]]:
    """``{"id", "mark", "area", "box"}`` of each cited id on the last frame (no box if absent)."""
    labels = check_segmentation(seg).label_maps[-1]
    registry = seg.registry
    out = []
    for i in whole_ids(ids, "ids", "MotionBit ids"):
        obj = instance_from_mask(labels == i, i)
        rec: dict[str, Any] = {"id": int(i), "mark": registry.number(i), "area": obj.area}
        if obj.area:
            rec["box"] = list(obj.bbox)
        out.append(rec)
    return out


def _vlm_name(vlm: Any) -> str:
    return str(getattr(vlm, "name", type(vlm).__name__))
