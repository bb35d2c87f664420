"""Grounded VQA: video -> label maps -> marked frames -> prompt -> answer -> cited masks."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np
from PIL import Image

from motionbits.frames import whole_number
from motionbits.objects import Instance, instances_from_labels

from .answers import ParsedAnswer, parse_answer
from .inputs import ImageLike, as_rgb_array, check_label_map
from .metadata import MarkInfo
from .prompts import load_prompt, mark_prompt_variables, prompt_variables
from .registry import MarkRegistry, MarkStyle
from .render import SetOfMarkRenderer
from .video import mark_video, sample_for_vlm

__all__ = ["Segmenter", "VLM", "GroundedVQAResult", "GroundedVQA"]


@runtime_checkable
class Segmenter(Protocol):
    """Anything callable as ``segmenter(frames) -> label maps``: T (H, W, 3) uint8 RGB
    frames in, T (H, W) integer label maps out (0 = background, k > 0 = object k,
    the same k for the same object on every frame). ``motionbits.MotionBitsSegmenter()``
    is one."""

    def __call__(self, frames: list[np.ndarray]) -> Sequence[np.ndarray]: ...


@runtime_checkable
class VLM(Protocol):
    """Anything with ``generate(frames, prompt, system=None, **gen) -> str`` (the
    ``vlm_adapters`` interface; its ``StubVLM`` answers from a script, for tests)."""

    def generate(
        self,
        frames: list["np.ndarray | Image.Image"],
        prompt: str,
        system: str | None = None,
        **gen: Any,
    ) -> str: ...


@dataclass
class GroundedVQAResult:
    """Every intermediate of one :class:`GroundedVQA` call.

    Attributes:
        frames: the input frames, (H, W, 3) uint8 RGB.
        label_maps: one (H, W) int64 label map per input frame.
        registry: object id -> mark number, fixed over the whole video.
        frame_indices: which input frames were shown to the VLM.
        marked_frames: those frames with marks, at the VLM's size.
        marks: id -> :class:`MarkInfo` of the marks shown (geometry in the VLM frames).
        prompt: the prompt sent.
        system: the system prompt sent (or None).
        answer: the VLM's text, after :func:`somprompt.answers.repair_text` (a lone
            UTF-16 surrogate becomes U+FFFD: the answer always encodes to UTF-8).
        parsed: citations found in the answer, with masks from the last label map
            (full resolution).
    """

    frames: list[np.ndarray]
    label_maps: list[np.ndarray]
    registry: MarkRegistry
    frame_indices: list[int]
    marked_frames: list[np.ndarray]
    marks: dict[int, MarkInfo]
    prompt: str
    system: str | None
    answer: str
    parsed: ParsedAnswer
    generation: dict[str, Any] = field(default_factory=dict)

    @property
    def cited_ids(self) -> list[int]:
        """Object ids cited in the answer, in order of first mention."""
        return self.parsed.ids

    @property
    def masks(self) -> dict[int, np.ndarray]:
        """Cited object id -> (H, W) bool mask on the last frame."""
        return self.parsed.masks

    @property
    def instances(self) -> list[Instance]:
        """The cited objects on the last frame as :class:`motionbits.Instance` (with masks),
        in order of first mention; ``motionbits.to_supervision`` takes them."""
        by_id = {obj.id: obj for obj in instances_from_labels(self.label_maps[-1])}
        return [by_id[i] for i in self.cited_ids if i in by_id]


class GroundedVQA:
    """Ask a VLM about a video with Set-of-Mark prompts and get masks back.

    video frames -> ``segmenter`` -> label maps -> marks drawn on ``num_frames``
    uniformly sampled frames, shrunk to ``max_side`` -> prompt from ``prompts/`` ->
    ``vlm.generate`` -> answer -> cited marks -> masks on the last frame.

    Args:
        segmenter: callable ``frames -> label maps`` (:class:`Segmenter`), e.g.
            ``motionbits.MotionBitsSegmenter()``.
        vlm: object with ``generate(frames, prompt, system=None, **gen) -> str``.
        prompt: template name (default ``"som_vqa"``, which needs ``question``).
        system_prompt: template name of the system prompt, or None for none.
        renderer: how marks are drawn (default ``SetOfMarkRenderer()``).
        style: ``"number"`` or ``"letter"`` marks.
        max_side: longest side of the frames sent to the VLM (None: full size).
        num_frames: frames sent (uniform sampling incl. first and last; None: all).
        prompts_dir: folder of templates (default: the templates installed with
            ``somprompt``, see :func:`default_prompts_dir`).
        generation: keyword arguments passed to ``vlm.generate`` on every call.

    Example:
        >>> import numpy as np
        >>> from somprompt.testing import FixedSegmenter
        >>> class SaysBox:  # any object with generate(frames, prompt, system=None, **gen) -> str
        ...     def generate(self, frames, prompt, system=None, **gen):
        ...         return "The box [1] moved."
        >>> frames = [np.zeros((48, 64, 3), np.uint8)] * 3
        >>> labels = np.zeros((48, 64), np.int32); labels[10:30, 10:30] = 4
        >>> vqa = GroundedVQA(FixedSegmenter([labels] * 3), SaysBox())
        >>> result = vqa(frames, question="What moved?")
        >>> result.cited_ids, int(result.masks[4].sum())
        ([4], 400)
    """

    def __init__(
        self,
        segmenter: Segmenter,
        vlm: VLM,
        *,
        prompt: str = "som_vqa",
        system_prompt: str | None = "som_system",
        renderer: SetOfMarkRenderer | None = None,
        style: MarkStyle = "number",
        max_side: int | None = 768,
        num_frames: int | None = 8,
        prompts_dir: "str | os.PathLike | None" = None,
        generation: Mapping[str, Any] | None = None,
    ) -> None:
        if not callable(segmenter):
            raise TypeError(
                f"segmenter must be callable as segmenter(frames) -> label maps, got "
                f"{type(segmenter).__name__}"
            )
        if not callable(getattr(vlm, "generate", None)):
            raise TypeError(
                f"vlm must have a generate(frames, prompt, system=None, **gen) method, got "
                f"{type(vlm).__name__}"
            )
        # checked now, not after segmenting (else num_frames=0 or max_side=0 failed in
        # sample_for_vlm, generation=5 with "'int' object is not iterable")
        if renderer is not None and not isinstance(renderer, SetOfMarkRenderer):
            raise TypeError(f"renderer must be a somprompt.SetOfMarkRenderer or None, got {type(renderer).__name__}")
        if max_side is not None and whole_number("max_side", max_side) < 1:
            raise ValueError(f"max_side must be >= 1 or None, got {max_side!r}")
        if num_frames is not None and whole_number("num_frames", num_frames) < 1:
            raise ValueError(f"num_frames must be >= 1 or None, got {num_frames!r}")
        if generation is not None and not isinstance(generation, Mapping):
            raise TypeError(f"generation must be a dict of keyword arguments for vlm.generate, "
                            f"got {type(generation).__name__}")
        self.segmenter = segmenter
        self.vlm = vlm
        self.prompt_name = prompt
        self.system_prompt_name = system_prompt
        self.renderer = renderer if renderer is not None else SetOfMarkRenderer()
        self.style: MarkStyle = style
        self.max_side = max_side
        self.num_frames = num_frames
        self.prompts_dir = prompts_dir
        self.generation = dict(generation or {})
        # fail now, not after segmenting, if a template is missing
        self._prompt_vars = prompt_variables(prompt, prompts_dir)
        self._system_vars = (
            prompt_variables(system_prompt, prompts_dir) if system_prompt is not None else []
        )

    def _segment(self, frames: list[np.ndarray]) -> list[np.ndarray]:
        maps = self.segmenter(frames)
        if isinstance(maps, np.ndarray) and maps.ndim == 3:
            return list(maps)
        if isinstance(maps, (list, tuple)):
            return list(maps)
        raise TypeError(
            f"the segmenter {type(self.segmenter).__name__} must return a list of (H, W) label "
            f"maps, one per frame; it returned {type(maps).__name__}"
        )

    def _prompts(
        self, registry: MarkRegistry, shown: list[int], question: str | None, prompt_vars: dict
    ) -> tuple[str, str | None]:
        """The prompt and system prompt for the marks ``shown``."""
        auto = mark_prompt_variables(registry, shown)
        if question is not None:
            auto["question"] = question
        values = {k: v for k, v in auto.items() if k in self._prompt_vars}
        values.update(prompt_vars)
        prompt = load_prompt(self.prompt_name, prompts_dir=self.prompts_dir, **values)
        if self.system_prompt_name is None:
            return prompt, None
        sys_values = {k: v for k, v in auto.items() if k in self._system_vars}
        return prompt, load_prompt(self.system_prompt_name, prompts_dir=self.prompts_dir, **sys_values)

    def __call__(
        self,
        frames: "Sequence[ImageLike] | np.ndarray",
        question: str | None = None,
        *,
        label_maps: Sequence[np.ndarray] | None = None,
        **prompt_vars: object,
    ) -> GroundedVQAResult:
        """Run the pipeline on one video.

        Args:
            frames: a video file or a folder of images (read with
                :func:`motionbits.video.iter_frames`), T frames ((H, W, 3) uint8 RGB arrays
                or PIL images) or a (T, H, W, 3) array.
            question: fills the template's ``question`` variable (``som_vqa``).
            label_maps: T label maps to use instead of calling the segmenter.
            **prompt_vars: other template variables (e.g. ``task`` for
                ``som_grasp_first``); override the automatic ones.

        Returns:
            :class:`GroundedVQAResult`.
        """
        if question is None and "question" in self._prompt_vars and "question" not in prompt_vars:
            raise ValueError(
                f"prompt template {self.prompt_name!r} needs a question: call vqa(frames, question=...)"
            )
        if question is not None and "question" not in self._prompt_vars:
            raise ValueError(
                f"prompt template {self.prompt_name!r} takes no question (it uses: "
                f"{', '.join(self._prompt_vars) or 'no variables'})"
            )
        if isinstance(frames, (str, os.PathLike)):
            from motionbits.video import iter_frames  # the video reader, not the segmenter

            frames = list(iter_frames(frames))
        if isinstance(frames, np.ndarray) and frames.ndim == 4:
            frames = list(frames)
        if isinstance(frames, (np.ndarray, Image.Image, bytes)) or not hasattr(frames, "__iter__"):
            raise TypeError(
                "frames must be a video file, a folder of images, a list of (H, W, 3) uint8 RGB "
                "frames or a (T, H, W, 3) array"
            )
        imgs = [as_rgb_array(f, name=f"frame {i}") for i, f in enumerate(frames)]
        if not imgs:
            raise ValueError("no frames given")
        maps = self._segment(imgs) if label_maps is None else list(label_maps)
        if len(maps) != len(imgs):
            source = "label_maps" if label_maps is not None else f"the segmenter {type(self.segmenter).__name__}"
            raise ValueError(f"{source} gave {len(maps)} label maps for {len(imgs)} frames; need one per frame")
        maps = [check_label_map(m, imgs[i].shape[:2], name=f"label map {i}") for i, m in enumerate(maps)]

        registry = MarkRegistry.from_label_maps(maps, self.style)
        small_frames, small_maps, idx = sample_for_vlm(imgs, maps, self.max_side, self.num_frames)
        marked = mark_video(small_frames, small_maps, self.renderer, registry=registry, frame_indices=idx)
        shown = list(marked.marks)  # ids visible on the frames sent, by mark number

        prompt, system = self._prompts(registry, shown, question, prompt_vars)

        answer = self.vlm.generate(list(marked.frames), prompt, system=system, **self.generation)
        if not isinstance(answer, str):
            raise TypeError(
                f"{type(self.vlm).__name__}.generate must return the answer text (str), got "
                f"{type(answer).__name__}"
            )
        parsed = parse_answer(answer, registry, labels=maps[-1])
        return GroundedVQAResult(
            frames=imgs, label_maps=maps, registry=registry, frame_indices=idx,
            marked_frames=list(marked.frames), marks=marked.marks, prompt=prompt, system=system,
            answer=parsed.answer, parsed=parsed, generation=dict(self.generation),
        )
