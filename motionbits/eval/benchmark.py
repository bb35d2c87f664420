"""Run segmentation methods over a MoRiBo dataset and score them (the paper's Table 2).

Each scene's frames are read once and given to every method; only the method call is
timed. Seconds per frame = total method time / total frames.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np
from tqdm import tqdm

from motionbits.eval.dataset import (
    discover_scenes, load_scene, summarize_tracks,
)
from motionbits.eval.kinds import body_kinds_and_roles, iou_by_kind
from motionbits.eval.labelmaps import write_label_map
from motionbits.eval.losses import loss_budget
from motionbits.eval.metrics import FrameScores, evaluate_frame
from motionbits.objects import check_label_map

__all__ = ["run_benchmark"]


def run_benchmark(
    data: str | os.PathLike,
    methods: dict[str, Callable[[list[np.ndarray]], np.ndarray]],
    *,
    save_pred: str | os.PathLike | None = None,
    max_scenes: int | None = None,
    progress: bool = True,
) -> tuple[dict[str, dict], dict[str, float]]:
    """Score every method on every scene of ``data``.

    Args:
        data: a MoRiBo scene, track or folder of tracks.
        methods: ``{name: method}``; a method maps a list of (H, W, 3) uint8 frames to the
            (H, W) int label map of the last frame; one with a true ``needs_scene``
            attribute also gets ``scene=`` the scene folder.
        save_pred: if given, write ``<save_pred>/<method>/<track>/<scene>.png`` (readable by
            ``motionbits eval``).
        max_scenes: score only the first scenes of each track.

    Returns:
        ``(results, seconds_per_frame)``: per method the dict of
        :func:`motionbits.eval.dataset.evaluate_dataset` (with its ``by_kind``,
        ``by_role`` and ``losses``), and its mean seconds per frame.
        A method that raises ImportError (its package or model is not installed) is
        dropped with a warning on stderr instead of stopping the run.

    Raises:
        ValueError: a scene's frames differ in size or from gt.png's, a method failed on a
            scene (e.g. one of a single frame), or returned a label map of the wrong shape or
            of non-integer values (names the method and the scene).
    """
    if not methods:
        raise ValueError("no method to run")
    scenes = discover_scenes(data, max_scenes)
    by_track: dict[str, dict[str, list[FrameScores]]] = {m: {} for m in methods}
    per_scene: dict[str, dict] = {m: {} for m in methods}
    seconds = {m: 0.0 for m in methods}
    unavailable: dict[str, str] = {}
    kinds: dict[str, dict[int, str]] = {}
    roles: dict[str, dict[int, str]] = {}
    n_frames = 0
    for scene in tqdm(scenes, desc="benchmark", unit="scene", disable=not progress):
        frames, gt, ignore = load_scene(scene)  # the frames and gt.png fit together
        kinds[scene.key], roles[scene.key] = body_kinds_and_roles(scene.path)
        n_frames += len(frames)
        for name, method in methods.items():
            if name in unavailable:
                continue
            t0 = time.perf_counter()
            try:
                pred = np.asarray(method(frames, scene=scene.path)
                                  if getattr(method, "needs_scene", False) else method(frames))
            except ImportError as exc:
                unavailable[name] = str(exc)
                print(f"benchmark: skipping method {name}: {exc}", file=sys.stderr)
                continue
            except ValueError as exc:  # e.g. a scene of one frame: say which scene
                raise ValueError(f"method {name} failed on scene {scene.key} ({len(frames)} "
                                 f"frames): {exc}") from exc
            seconds[name] += time.perf_counter() - t0
            if pred.shape != gt.shape:
                raise ValueError(f"method {name} returned shape {pred.shape} for scene "
                                 f"{scene.key}, ground truth is {gt.shape}")
            # integer ids only: a float map would be truncated silently by a cast
            pred = check_label_map(pred, name=f"the label map of method {name} for scene {scene.key}")
            scores = evaluate_frame(pred, gt, ignore)
            by_track[name].setdefault(scene.track, []).append(scores)
            per_scene[name][scene.key] = scores.to_dict()
            if save_pred is not None:
                write_label_map(Path(save_pred) / name / scene.track / f"{scene.name}.png", pred)
    results = {}
    for name in methods:
        if name in unavailable:
            continue
        results[name] = {**summarize_tracks(by_track[name]), "per_scene": per_scene[name],
                         "by_kind": iou_by_kind(per_scene[name], kinds),
                         "by_role": iou_by_kind(per_scene[name], roles),
                         "losses": loss_budget(per_scene[name])}
    if not results:
        raise ImportError(f"no method could run: {unavailable}")
    spf = {m: seconds[m] / max(n_frames, 1) for m in results}
    return results, spf
