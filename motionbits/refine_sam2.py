"""SAM2 refinement of MotionBit masks (``MotionBitsConfig(refine="sam2", sam2_path=...)``).

The paper ends its pipeline with SAM2 prompted per MotionBit for sharp boundaries. This
module does that as a pure post-step on one frame: ``refine(frame, labels, result) ->
(labels, stats)``. The segmenter's own state (label history, tracking) never sees the
refined masks, so refinement cannot change which MotionBits exist or their ids.

Per MotionBit k of a frame, SAM2 (transformers' ``Sam2Model``, one image encoding and one
batched mask decoding per frame) gets

* its box (the bounding box of its motion mask),
* positive points: up to ``N_POSITIVE`` of its own grid nodes, spread over it (the deepest
  one first, then farthest-point order),
* negative points: up to ``N_NEGATIVE`` nodes of its neighbourhood (a ring of ``RING``
  grid nodes around it) that carry another label: static background or a neighbouring
  MotionBit.

A refined mask must agree with the motion evidence, or it is rejected and the motion mask
stays; the reasons are counted:

* ``"empty"``: SAM2 returned no pixel;
* ``"background"``: more than ``max_outside`` of the refined mask lies on static
  background (label 0) farther than ``BAND_CELLS`` grid cells from the motion mask, i.e. it
  grew onto what the motion says is static;
* ``"low_iou"``: its IoU with the motion mask is below ``min_iou`` (another object, or a
  part of this one).

An accepted mask replaces the motion mask of k: pixels of k outside it go to background,
and it claims background pixels; pixels of other MotionBits are never taken.

torch and transformers are imported when a `Sam2Refiner` is loaded, never at import time.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np
from scipy import ndimage

from motionbits.frames import fraction, whole_number
from motionbits.objects import check_label_map
from motionbits.torch_threads import check_threads, torch_threads

if TYPE_CHECKING:  # pragma: no cover
    from motionbits.segmenter import MotionBitsResult

__all__ = ["REFINERS", "REJECT_REASONS", "Sam2Prompt", "Sam2Refiner", "build_prompts", "judge_refinement",
           "merge_refinements", "node_centres"]

#: Accepted values of ``MotionBitsConfig.refine``.
REFINERS = ("none", "sam2")
#: Reasons a refined mask is rejected, in the order they are tested.
REJECT_REASONS = ("empty", "background", "low_iou")

N_POSITIVE = 4  # ours: positive points per MotionBit, from its own nodes
N_NEGATIVE = 4  # ours: negative points per MotionBit, from nodes of other labels around it
RING = 2  # ours: width, in grid nodes, of the neighbourhood the negative points come from
BAND_CELLS = 2.0  # ours: growth within this many grid cells of the motion mask is boundary
_PAD_LABEL = -10  # transformers' SAM2 label of a padding point (ignored by the prompt encoder)


@dataclass(frozen=True)
class Sam2Prompt:
    """The SAM2 prompt of one MotionBit (coordinates in input pixels).

    Attributes:
        id: the MotionBit's id.
        box: (x0, y0, x1, y1) of its motion mask, x1/y1 exclusive.
        points: (P, 2) float32 (x, y) prompt points.
        point_labels: (P,) int64, 1 = positive (on the MotionBit), 0 = negative.
    """

    id: int
    box: tuple[float, float, float, float]
    points: np.ndarray
    point_labels: np.ndarray


def _count(name: str, value: Any, low: int) -> int:
    """``value`` as an int >= ``low`` (2.5 was read as 2 points, -1 and 0 as none or as 1)."""
    n = whole_number(name, value)
    if n < low:
        raise ValueError(f"{name} must be >= {low}, got {value!r}")
    return n


def _check_mask(name: str, mask: Any, shape: tuple[int, ...], of: str = "the label map") -> None:
    """``mask`` an (H, W) bool array of ``shape`` (a float mask failed in numpy's bitwise_and,
    a NaN one in int(), one of another size in broadcasting)."""
    if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_:
        raise TypeError(f"{name} must be an (H, W) bool numpy array, got "
                        f"{type(mask).__name__}{'' if not isinstance(mask, np.ndarray) else ' of ' + str(mask.dtype)}")
    if mask.shape != tuple(shape):
        raise ValueError(f"{name} has shape {mask.shape} but {of} is {tuple(shape)}; masks must have its (H, W)")


def node_centres(shape: tuple[int, int], rows: int, cols: int) -> np.ndarray:
    """(rows * cols, 2) float32 (x, y) of the grid nodes in an image of `shape` (H, W),
    row-major: the cell centres of the segmenter's node grid, scaled to that image."""
    if not isinstance(shape, (tuple, list)) or len(shape) != 2:  # else "too many values to unpack"
        raise ValueError(f"shape must be the image's (H, W), got {shape!r:.40}")
    h, w = (_count("shape", v, 1) for v in shape)
    rows, cols = _count("rows", rows, 1), _count("cols", cols, 1)  # 0: ZeroDivisionError
    gx, gy = np.meshgrid((np.arange(cols) + 0.5) * (w / cols), (np.arange(rows) + 0.5) * (h / rows))
    return np.stack([gx.ravel(), gy.ravel()], axis=1).astype(np.float32)


def _spread(candidates: np.ndarray, xy: np.ndarray, first: int, k: int) -> np.ndarray:
    """Up to `k` of the `candidates` (indices into `xy`), farthest-point order from `first`."""
    if len(candidates) == 0 or k <= 0:
        return candidates[:0]
    chosen = [first]
    dist = np.linalg.norm(xy[candidates] - xy[first], axis=1)
    while len(chosen) < min(k, len(candidates)):
        nxt = int(np.argmax(dist))
        if dist[nxt] <= 0:
            break
        chosen.append(int(candidates[nxt]))
        dist = np.minimum(dist, np.linalg.norm(xy[candidates] - xy[candidates[nxt]], axis=1))
    return np.asarray(chosen, np.int64)


def build_prompts(labels: np.ndarray, node_labels: np.ndarray, ids: list[int] | None = None, *,
                  n_positive: int = N_POSITIVE, n_negative: int = N_NEGATIVE,
                  ring: int = RING) -> list[Sam2Prompt]:
    """One SAM2 prompt per MotionBit from the segmenter's output.

    Args:
        labels: (H, W) int label map at the input size (0 = background).
        node_labels: (rows, cols) int MotionBit id of every grid node (0 = none).
        ids: the MotionBits to prompt (default: every id > 0 in `labels`, ascending).
        n_positive, n_negative: most positive / negative points per MotionBit.
        ring: neighbourhood width in grid nodes for the negative points.

    Returns:
        prompts in the order of `ids`. Positive points are nodes of k whose pixel is also
        labelled k (the deepest inside k's node set first); a MotionBit with no such node
        (its mask is carried from earlier frames) gets its mask's deepest pixel instead
        (nearest the centroid among ties).
        Negative points are nodes in the `ring` around k's nodes whose pixel label is not k.
    """
    labels = check_label_map(labels, name="labels")  # float: "cannot be interpreted as an integer"
    node_labels = check_label_map(node_labels, name="node_labels")
    if node_labels.size == 0:  # else ZeroDivisionError
        raise ValueError(f"node_labels must be the (rows, cols) node grid, got shape {node_labels.shape}")
    if ids is not None:
        if isinstance(ids, (str, bytes)) or not hasattr(ids, "__iter__"):
            raise TypeError(f"ids must be a list of MotionBit ids or None, got {type(ids).__name__} {ids!r:.40}")
        ids = [_count("ids", k, 1) for k in ids]  # 3.5: "list indices must be integers", -2: a prompt of id -2
    n_positive = _count("n_positive", n_positive, 1)
    n_negative = _count("n_negative", n_negative, 0)
    ring = _count("ring", ring, 1)
    rows, cols = node_labels.shape
    h, w = labels.shape
    xy = node_centres((h, w), rows, cols)
    px = np.clip(xy[:, 0].astype(np.int64), 0, w - 1)
    py = np.clip(xy[:, 1].astype(np.int64), 0, h - 1)
    pixel_at_node = labels[py, px]
    node_flat = node_labels.ravel()
    boxes = ndimage.find_objects(labels)
    if ids is None:
        ids = [i + 1 for i, b in enumerate(boxes) if b is not None]
    prompts = []
    for k in ids:
        box = boxes[k - 1] if k - 1 < len(boxes) else None
        if box is None:
            raise ValueError(f"MotionBit {k} has no pixel in the label map")
        own_grid = (node_labels == k) & (pixel_at_node == k).reshape(rows, cols)
        own = np.flatnonzero(own_grid)
        if len(own):
            depth = ndimage.distance_transform_cdt(np.pad(own_grid, 1)).ravel()
            depth = depth.reshape(rows + 2, cols + 2)[1:-1, 1:-1].ravel()
            pos = xy[_spread(own, xy, int(own[np.argmax(depth[own])]), n_positive)]
        else:  # no node of its own this frame: the deepest pixel of its mask
            sub = labels[box] == k
            d = cv2.distanceTransform(np.pad(sub, 1).astype(np.uint8), cv2.DIST_L2, 3)[1:-1, 1:-1]
            ys, xs = np.nonzero(d >= d.max() - 0.5)  # ties (a ridge): the one nearest the centroid
            cy, cx = ndimage.center_of_mass(sub)
            i = int(np.argmin((ys - cy) ** 2 + (xs - cx) ** 2))
            y, x = ys[i], xs[i]
            pos = np.array([[x + box[1].start + 0.5, y + box[0].start + 0.5]], np.float32)
        near = ndimage.binary_dilation(node_flat.reshape(rows, cols) == k, np.ones((3, 3), bool),
                                       iterations=max(1, ring)).ravel()
        cand = np.flatnonzero(near & (pixel_at_node != k) & (node_flat != k))
        if len(cand):
            centre = xy[own].mean(axis=0) if len(own) else pos[0]
            first = int(cand[np.argmin(np.linalg.norm(xy[cand] - centre, axis=1))])
            neg = xy[_spread(cand, xy, first, n_negative)]
        else:
            neg = np.zeros((0, 2), np.float32)
        prompts.append(Sam2Prompt(
            id=int(k),
            box=(float(box[1].start), float(box[0].start), float(box[1].stop), float(box[0].stop)),
            points=np.concatenate([pos, neg]).astype(np.float32),
            point_labels=np.concatenate([np.ones(len(pos), np.int64), np.zeros(len(neg), np.int64)]),
        ))
    return prompts


def judge_refinement(refined: np.ndarray, motion: np.ndarray, static: np.ndarray, band_px: float,
                     *, min_iou: float, max_outside: float) -> str | None:
    """Why a refined mask is rejected (one of `REJECT_REASONS`), or None if it is accepted.

    Args:
        refined, motion, static: (H, W) bool: SAM2's mask, the MotionBit's motion mask and
            the static background (label 0 in the motion labels).
        band_px: growth within this distance (px) of the motion mask counts as boundary.
        min_iou, max_outside: see ``MotionBitsConfig.refine_min_iou`` / ``refine_max_outside``.
    """
    if not isinstance(motion, np.ndarray) or motion.ndim != 2:
        raise ValueError(f"motion must be an (H, W) bool mask, got shape {np.shape(motion)}")
    _check_mask("motion", motion, motion.shape)
    _check_mask("refined", refined, motion.shape, "motion")
    _check_mask("static", static, motion.shape, "motion")
    if isinstance(band_px, bool) or not isinstance(band_px, numbers.Real) or not band_px >= 0:
        raise ValueError(f"band_px must be a number >= 0, got {band_px!r:.40}")  # NaN, inf: int() failed
    min_iou, max_outside = fraction("min_iou", min_iou), fraction("max_outside", max_outside)
    area = int(refined.sum())
    if area == 0:
        return "empty"
    # a band beyond the image's diagonal covers it all, as the diagonal does (1e6 px: a 4 TB kernel)
    r = max(1, int(np.ceil(min(band_px, math.hypot(*motion.shape)))))
    near = cv2.dilate(motion.astype(np.uint8), cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1,) * 2))
    outside = int((refined & static & ~near.astype(bool)).sum())
    if outside > max_outside * area:
        return "background"
    iou = (refined & motion).sum() / (refined | motion).sum()
    if iou < min_iou:
        return "low_iou"
    return None


def merge_refinements(labels: np.ndarray, accepted: dict[int, np.ndarray]) -> np.ndarray:
    """(H, W) int32 labels with each accepted (H, W) bool mask replacing its MotionBit's mask.

    Pixels of k outside its refined mask become background; the refined mask claims
    background pixels (first come, in ascending id) and never another MotionBit's pixels.
    """
    labels = check_label_map(labels, name="labels")
    if not isinstance(accepted, dict):  # None: "not iterable"; a list: "only integer scalar arrays"
        raise TypeError(f"accepted must be a dict of MotionBit id -> (H, W) bool mask, got {type(accepted).__name__}")
    for k, mask in accepted.items():
        _count("accepted's ids", k, 1)
        _check_mask(f"accepted[{k!r}]", mask, labels.shape)
    if labels.size and labels.max() > np.iinfo(np.int32).max:  # else wrapped in the int32 result
        raise ValueError(f"labels holds ids beyond int32 (max {labels.max()}); the refined map is int32")
    out = labels.astype(np.int32, copy=True)
    for k in sorted(accepted):
        mask, own = accepted[k], labels == k
        out[own & ~mask] = 0
        out[mask & (labels == 0) & (out == 0)] = k
    return out


class Sam2Refiner:
    """SAM2 prompted per MotionBit, with rejection of refinements the motion contradicts.

    Args:
        model: a transformers ``Sam2Model`` (on its device, eval mode).
        processor: its ``Sam2Processor``.
        min_iou: reject a refined mask whose IoU with the motion mask is below this.
        max_outside: reject a refined mask with more than this fraction of its pixels on
            static background beyond ``BAND_CELLS`` grid cells of the motion mask.
        threads: torch CPU threads for the model call. Default ``None`` keeps the caller's
            count: one inside `MotionBitsSegmenter.update` (on a busy 2-core machine, two
            threads made SAM2 2-10x slower); on an idle many-core CPU pass the core count.

    Attributes:
        totals: counts over all frames refined so far: ``frames``, ``prompted``,
            ``accepted`` and ``rejected`` (a dict reason -> count).
        last_stats: the stats of the latest frame (see `refine`).

    Use `from_pretrained` to load a checkpoint folder.
    """

    def __init__(self, model: Any, processor: Any, *, min_iou: float = 0.5, max_outside: float = 0.1,
                 threads: int | None = None) -> None:
        self.threads = check_threads(threads, "SAM2")
        self.model = model
        self.processor = processor
        self.min_iou = fraction("min_iou", min_iou)  # NaN accepted every refined mask
        self.max_outside = fraction("max_outside", max_outside)
        self.totals: dict[str, Any] = {"frames": 0, "prompted": 0, "accepted": 0,
                                       "rejected": dict.fromkeys(REJECT_REASONS, 0)}
        self.last_stats: dict[str, Any] = {}

    @classmethod
    def from_pretrained(cls, path_or_id: str | os.PathLike, *, device: Any = None, **kwargs: Any) -> Sam2Refiner:
        """Load ``Sam2Model`` + ``Sam2Processor`` from a local folder (or a reachable hub id).

        `kwargs` go to the constructor (`min_iou`, `max_outside`, `threads`).

        Raises:
            FileNotFoundError: a local path that does not exist.
            MissingDependencyError: torch / transformers missing or failing to import.
        """
        from motionbits.objects import MissingDependencyError, require, require_attr
        from vlm_adapters.base import check_local_path, resolve_device

        path = check_local_path(path_or_id, what="SAM2 checkpoint")
        transformers = require("transformers", "sam2", "SAM2 refinement")
        require("torch", "sam2", "SAM2 refinement")
        model_cls = require_attr(transformers, "Sam2Model", "sam2", "SAM2 refinement")
        processor_cls = require_attr(transformers, "Sam2Processor", "sam2", "SAM2 refinement")
        try:
            model = model_cls.from_pretrained(path)
            processor = processor_cls.from_pretrained(path)
        except ImportError as exc:  # e.g. the image processor's torchvision fails to load
            raise MissingDependencyError(
                f"SAM2 refinement could not load '{path_or_id}' (a module it needs failed to import): "
                f"{type(exc.__cause__ or exc).__name__}: {exc.__cause__ or exc}. "
                f"Repair the install: pip install \"motionbits[sam2]\"") from exc
        except OSError as exc:
            raise OSError(f"could not load a SAM2 checkpoint from '{path_or_id}': {exc}") from exc
        model.to(resolve_device(device)).eval()
        return cls(model, processor, **kwargs)

    @classmethod
    def from_config(cls, config: Any) -> Sam2Refiner:
        """The refiner a `MotionBitsConfig` asks for (``refine="sam2"``)."""
        return cls.from_pretrained(config.sam2_path, min_iou=config.refine_min_iou,
                                   max_outside=config.refine_max_outside)

    def predict(self, frame: np.ndarray, prompts: list[Sam2Prompt]) -> np.ndarray:
        """SAM2's masks for the prompts: (len(prompts), H, W) bool; one image encoding and
        one batched mask decoding (all prompts at once)."""
        import torch

        h, w = frame.shape[:2]
        if not prompts:
            return np.zeros((0, h, w), bool)
        n_points = max(len(p.points) for p in prompts)
        points = np.zeros((1, len(prompts), n_points, 2), np.float32)
        point_labels = np.full((1, len(prompts), n_points), _PAD_LABEL, np.int64)
        for i, p in enumerate(prompts):
            points[0, i, :len(p.points)] = p.points
            point_labels[0, i, :len(p.points)] = p.point_labels
        frame = frame if frame.flags.writeable else frame.copy()  # torch.from_numpy warns on read-only
        inputs = self.processor(images=frame, input_boxes=[[list(p.box) for p in prompts]],
                                input_points=points.tolist(), input_labels=point_labels.tolist(),
                                return_tensors="pt")
        device = next(self.model.parameters()).device
        inputs = inputs.to(device)
        inputs["pixel_values"] = inputs["pixel_values"].to(self.model.dtype)
        with torch_threads(self.threads), torch.inference_mode():
            out = self.model(pixel_values=inputs["pixel_values"], input_points=inputs["input_points"],
                             input_labels=inputs["input_labels"], input_boxes=inputs["input_boxes"],
                             multimask_output=False)
        masks = self.processor.post_process_masks(out.pred_masks.cpu(), inputs["original_sizes"].cpu())[0]
        return masks[:, 0].numpy().astype(bool)

    def refine(self, frame: np.ndarray, labels: np.ndarray, result: MotionBitsResult
               ) -> tuple[np.ndarray, dict[str, Any]]:
        """Refined labels of one frame and what happened.

        Args:
            frame: (H, W, 3) uint8 RGB input frame.
            labels: (H, W) int label map of the frame (0 = background).
            result: the segmenter's result for the frame (its ``node_labels`` give the points).

        Returns:
            (H, W) int32 labels with the same ids, and stats: ``prompted``, ``accepted``,
            ``rejected`` (reason -> count) and ``decisions`` (id -> "accepted" or the reason).
        """
        prompts = build_prompts(labels, result.node_labels)
        masks = self.predict(frame, prompts)
        rows, cols = result.node_labels.shape
        band = BAND_CELLS * max(labels.shape[0] / rows, labels.shape[1] / cols)
        static = labels == 0
        accepted, decisions = {}, {}
        for p, mask in zip(prompts, masks):
            reason = judge_refinement(mask, labels == p.id, static, band, min_iou=self.min_iou,
                                      max_outside=self.max_outside)
            decisions[p.id] = reason or "accepted"
            if reason is None:
                accepted[p.id] = mask
        rejected = dict.fromkeys(REJECT_REASONS, 0)
        for d in decisions.values():
            if d != "accepted":
                rejected[d] += 1
        stats = {"prompted": len(prompts), "accepted": len(accepted), "rejected": rejected,
                 "decisions": decisions}
        return merge_refinements(labels, accepted), stats

    def apply(self, frame: np.ndarray, result: MotionBitsResult) -> MotionBitsResult:
        """`result` with refined labels and re-measured MotionBit records (area, bbox,
        centroid), plus ``timings["refine"]`` (ms); the frame's stats (see `refine`) go to
        `last_stats` and are counted into `totals`."""
        from motionbits.video import as_rgb_frame

        t0 = time.perf_counter()
        labels, stats = self.refine(as_rgb_frame(frame), result.labels, result)
        self.last_stats = stats
        self.totals["frames"] += 1
        self.totals["prompted"] += stats["prompted"]
        self.totals["accepted"] += stats["accepted"]
        for reason, n in stats["rejected"].items():
            self.totals["rejected"][reason] += n
        boxes = ndimage.find_objects(labels)
        records = []
        for mb in result.motionbits:
            box = boxes[mb.id - 1] if mb.id - 1 < len(boxes) else None
            if box is None:  # an accepted mask that claimed no pixel (possible only with min_iou=0)
                continue
            ys, xs = np.nonzero(labels[box] == mb.id)
            records.append(dataclasses.replace(
                mb, area=int(len(xs)), bbox=(box[1].start, box[0].start, box[1].stop, box[0].stop),
                centroid=(float(xs.mean() + box[1].start), float(ys.mean() + box[0].start))))
        timings = dict(result.timings, refine=1000 * (time.perf_counter() - t0))
        return dataclasses.replace(result, labels=labels, motionbits=records, timings=timings)
