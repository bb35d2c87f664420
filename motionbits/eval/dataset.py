"""MoRiBo-format folders: scenes, tracks, ground truth, predictions, and dataset scoring.

Layout (see docs/evaluation.md)::

    <scene>/frames/00000.jpg ...   ordered frames (any image suffix)
    <scene>/gt.png                 16-bit (or 8-bit / indexed) label map of the final frame
    <scene>/meta.json              free-form metadata
    <scene>/ignore.png             optional: non-zero = pixel left out of both maps
    <track>/<scene>/...            a track is a folder of scenes
    <root>/<track>/<scene>/...     a dataset is a folder of tracks (or a single track)

Predictions (``--pred``) mirror the GT: per scene either ``<scene>.png`` or the output
folder ``<scene>/`` of ``motionbits segment``, whose last ``labels/NNNNN.png`` is used;
with several tracks, under ``<pred>/<track>/`` (a flat ``<pred>/`` is also searched).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from tqdm import tqdm

from motionbits.eval.kinds import body_kinds_and_roles, iou_by_kind
from motionbits.eval.labelmaps import read_label_map
from motionbits.eval.losses import loss_budget
from motionbits.eval.metrics import FP_KEYS, METRIC_KEYS, FrameScores, evaluate_frame, summarize
from motionbits.frames import whole_number
from motionbits.video import check_no_broken_links, frame_order, is_frame_file

__all__ = [
    "Scene", "discover_scenes", "is_scene", "scene_frames", "load_frames", "load_ground_truth",
    "load_scene",
    "find_prediction", "read_prediction", "evaluate_dataset", "average_blocks", "summarize_tracks",
]


@dataclass(frozen=True)
class Scene:
    """One MoRiBo scene: its track name, scene name and folder."""

    track: str
    name: str
    path: Path

    @property
    def key(self) -> str:
        return f"{self.track}/{self.name}"


def is_scene(path: Path) -> bool:
    """A folder is a scene if it holds ``gt.png`` or a ``frames/`` folder."""
    return path.is_dir() and ((path / "gt.png").is_file() or (path / "frames").is_dir())


def discover_scenes(root: str | os.PathLike, max_per_track: int | None = None) -> list[Scene]:
    """List the scenes under a scene folder, a track folder or a folder of tracks.

    Args:
        root: the folder.
        max_per_track: keep only the first scenes (by name) of each track.

    Returns:
        Scenes sorted by (track, name). A single scene gets its parent's name as track; a
        track folder its own name.

    Raises:
        FileNotFoundError: ``root`` does not exist.
        ValueError: no scene found, or ``max_per_track`` < 1.
        TypeError: ``max_per_track`` is not a whole number.
    """
    if max_per_track is not None:  # 0 or -1 kept no scene: every score NaN, no error
        max_per_track = whole_number("max_per_track", max_per_track)
        if max_per_track < 1:
            raise ValueError(f"max_per_track must be >= 1 or None, got {max_per_track}")
    scenes = _find_scenes(Path(root))
    if max_per_track is None:
        return scenes
    count: dict[str, int] = {}
    keep = []
    for scene in scenes:
        count[scene.track] = count.get(scene.track, 0) + 1
        if count[scene.track] <= max_per_track:
            keep.append(scene)
    return keep


def _find_scenes(root: Path) -> list[Scene]:
    if not root.is_dir():
        raise FileNotFoundError(f"dataset folder not found: {root}")
    if is_scene(root):
        return [Scene(root.resolve().parent.name, root.name, root)]
    subdirs = sorted(p for p in root.iterdir() if p.is_dir())
    scenes = [Scene(root.resolve().name, p.name, p) for p in subdirs if is_scene(p)]
    if scenes:
        return scenes
    for track in subdirs:
        scenes += [Scene(track.name, p.name, p)
                   for p in sorted(q for q in track.iterdir() if q.is_dir()) if is_scene(p)]
    if not scenes:
        raise ValueError(
            f"no MoRiBo scene under {root}: a scene is a folder with gt.png and frames/; "
            "pass a scene, a track (folder of scenes) or a folder of tracks"
        )
    return scenes


def scene_frames(scene: Scene | Path) -> list[Path]:
    """The scene's frame files in order (``frames/*`` sorted by name, numbers by value;
    hidden ``.*`` files and folders are skipped)."""
    path = scene.path if isinstance(scene, Scene) else Path(scene)
    folder = path / "frames"
    if not folder.is_dir():
        raise FileNotFoundError(f"scene {path} has no frames/ folder")
    check_no_broken_links(folder)
    files = sorted((p for p in folder.iterdir() if is_frame_file(p)), key=frame_order)
    if not files:
        raise ValueError(f"{folder} holds no frame images")
    return files


def load_frames(scene: Scene | Path) -> list[np.ndarray]:
    """The scene's frames as a list of (H, W, 3) uint8 RGB arrays (16-bit images scaled)."""
    from motionbits.video import read_image

    return [read_image(f) for f in scene_frames(scene)]


def load_ground_truth(scene: Scene | Path) -> tuple[np.ndarray, np.ndarray | None]:
    """Read ``gt.png`` and the optional ``ignore.png`` of a scene.

    Returns:
        ``(gt, ignore)``: (H, W) int32 labels and (H, W) bool or None.

    Raises:
        FileNotFoundError: no gt.png.
        ValueError: ignore.png has another shape than gt.png.
    """
    path = scene.path if isinstance(scene, Scene) else Path(scene)
    gt_file = path / "gt.png"
    if not gt_file.is_file():
        raise FileNotFoundError(f"scene {path} has no gt.png (16-bit label map of the last frame)")
    gt = read_label_map(gt_file)
    ignore = None
    if (path / "ignore.png").is_file():
        ignore = read_label_map(path / "ignore.png") > 0
        if ignore.shape != gt.shape:
            raise ValueError(f"{path}/ignore.png is {ignore.shape}, gt.png is {gt.shape}")
    return gt, ignore


def load_scene(scene: Scene | Path) -> tuple[list[np.ndarray], np.ndarray, np.ndarray | None]:
    """The frames and ground truth of a scene, checked to fit together (for running
    methods on it: a method predicts at the frames' size).

    Returns:
        ``(frames, gt, ignore)``: the (H, W, 3) uint8 frames (:func:`load_frames`) and
        :func:`load_ground_truth`'s (H, W) maps.

    Raises:
        FileNotFoundError: no gt.png or no frames/.
        ValueError: the frames differ in size, or gt.png is not the frames' size.
    """
    path = scene.path if isinstance(scene, Scene) else Path(scene)
    files = scene_frames(path)
    frames = load_frames(path)
    h, w = frames[0].shape[:2]
    for f, frame in zip(files, frames):
        if frame.shape[:2] != (h, w):
            raise ValueError(f"scene {path}: frame {f.name} is {frame.shape[1]}x{frame.shape[0]} "
                             f"but {files[0].name} is {w}x{h}; the frames of a scene share one size")
    gt, ignore = load_ground_truth(path)
    if gt.shape != (h, w):
        raise ValueError(f"scene {path}: gt.png is {gt.shape[1]}x{gt.shape[0]} but the frames are "
                         f"{w}x{h}; gt.png must be the last frame's label map at the frames' size")
    return frames, gt, ignore


def find_prediction(pred_root: str | os.PathLike, scene: Scene) -> Path | None:
    """Where the prediction of ``scene`` lies under ``pred_root`` (None if nowhere).

    Looked up in order: ``<pred>/<track>/<scene>.png``, ``<pred>/<track>/<scene>/``,
    ``<pred>/<scene>.png``, ``<pred>/<scene>/``; a folder must hold ``labels/*.png``.
    """
    root = Path(pred_root)
    for base in (root / scene.track, root):
        if (base / f"{scene.name}.png").is_file():
            return base / f"{scene.name}.png"
        if (base / scene.name / "labels").is_dir():
            return base / scene.name
    return None


def read_prediction(path: str | os.PathLike) -> np.ndarray:
    """Read a prediction: a label-map PNG, or a segment output folder (last ``labels/*.png``)."""
    path = Path(path)
    if path.is_dir():  # by frame number: 100000.png (a 6-digit index) comes after 99999.png
        maps = (sorted((m for m in (path / "labels").glob("*.png") if is_frame_file(m)),
                       key=frame_order) if (path / "labels").is_dir() else [])
        if not maps:
            raise ValueError(f"prediction folder {path} has no labels/NNNNN.png label maps")
        path = maps[-1]
    return read_label_map(path)


def average_blocks(blocks: list[dict[str, float]], keys: tuple[str, ...] = METRIC_KEYS
                   ) -> dict[str, float]:
    """Key-wise mean of summary blocks, ignoring NaN (used to average over tracks)."""
    out = {}
    for key in keys:
        vals = [b[key] for b in blocks if b.get(key) is not None and not np.isnan(b[key])]
        out[key] = float(np.mean(vals)) if vals else float("nan")
    return out


def summarize_tracks(by_track: dict[str, list[FrameScores]]) -> dict:
    """Per-track summaries and their mean over tracks.

    Returns:
        ``{"macro", "pooled", "false_positives"}`` (each the mean over tracks of the track
        blocks) and ``"tracks": {track: summarize(frames)}``.
    """
    tracks = {t: summarize(fs) for t, fs in by_track.items()}
    return {
        "macro": average_blocks([s["macro"] for s in tracks.values()]),
        "pooled": average_blocks([s["pooled"] for s in tracks.values()]),
        "false_positives": average_blocks([s["false_positives"] for s in tracks.values()],
                                          FP_KEYS),
        "tracks": tracks,
    }


def evaluate_dataset(
    gt_root: str | os.PathLike,
    predict: str | os.PathLike | Callable[[Scene], np.ndarray],
    *,
    missing: str = "error",
    progress: bool = True,
) -> dict:
    """Score predictions against every scene of a MoRiBo dataset.

    Args:
        gt_root: a scene, a track or a folder of tracks (see module docstring).
        predict: a prediction folder, or a callable ``scene -> (H, W) int label map``.
        missing: ``"error"`` (default) raises when a scene has no prediction; ``"empty"``
            scores it as an empty prediction.
        progress: show a tqdm bar.

    Returns:
        :func:`summarize_tracks` of the scenes (``"macro"``, ``"pooled"``,
        ``"false_positives"`` averaged over tracks, ``"tracks"``) and ``"per_scene":
        {"track/scene": FrameScores.to_dict()}`` and ``"by_kind"`` (mean IoU per track and
        kind of body, :func:`motionbits.eval.kinds.iou_by_kind`; empty where ``meta.json``
        names no kinds) and ``"by_role"`` (the same per role of body,
        :func:`motionbits.eval.kinds.body_roles`) and ``"losses"`` (each track's
        ``100 - mIoU`` by how each body's mark fails, :func:`motionbits.eval.losses.loss_budget`,
        in points); scores are fractions in [0, 1] except
        ``spurious`` (predicted objects per scene).
    """
    if missing not in ("error", "empty"):
        raise ValueError(f"missing must be 'error' or 'empty', got {missing!r}")
    scenes = discover_scenes(gt_root)
    by_track: dict[str, list[FrameScores]] = {}
    per_scene = {}
    kinds: dict[str, dict[int, str]] = {}
    roles: dict[str, dict[int, str]] = {}
    for scene in tqdm(scenes, desc="evaluate", unit="scene", disable=not progress):
        gt, ignore = load_ground_truth(scene)
        if callable(predict):
            pred = np.asarray(predict(scene))
        else:
            where = find_prediction(predict, scene)
            if where is None:
                if missing == "error":
                    raise FileNotFoundError(
                        f"no prediction for scene {scene.key} under {predict} (expected "
                        f"{scene.name}.png or {scene.name}/labels/; --missing empty scores "
                        "missing scenes as empty predictions)"
                    )
                pred = np.zeros_like(gt)
            else:
                pred = read_prediction(where)
        try:
            scores = evaluate_frame(pred, gt, ignore)
        except ValueError as exc:
            raise ValueError(f"scene {scene.key}: {exc}") from exc
        by_track.setdefault(scene.track, []).append(scores)
        per_scene[scene.key] = scores.to_dict()
        kinds[scene.key], roles[scene.key] = body_kinds_and_roles(scene.path)
    return {**summarize_tracks(by_track), "per_scene": per_scene,
            "by_kind": iou_by_kind(per_scene, kinds), "by_role": iou_by_kind(per_scene, roles),
            "losses": loss_budget(per_scene)}
