"""Mean IoU per kind of body: which kinds of bodies a method misses.

A track's mIoU mixes the agent (a gripper or hand, large and always moving) with the bodies
it moves; a drop on laptop lids or glued composites hides in it. Scenes made by
``motionbits synth`` name each ground-truth body's kind in ``meta.json``
(``{"labels": {"1": {"kind": "laptop", ...}, ...}}``); scenes without it are left out.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

__all__ = ["body_kinds", "iou_by_kind", "format_kinds"]


def body_kinds(scene: str | Path) -> dict[int, str]:
    """Ground-truth id -> kind of body, from a scene's ``meta.json`` (``labels.<id>.kind``).

    Returns ``{}`` when the scene has no ``meta.json``, it is not JSON, or it names no
    kinds (``meta.json`` is free-form; a DAVIS window has none). An entry whose id is not
    a whole number >= 1 is skipped, not the scene's every kind.
    """
    try:
        meta = json.loads((Path(scene) / "meta.json").read_text())
        labels = meta["labels"]
        items = labels.items()
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError):
        return {}  # RecursionError: brackets nested thousands deep
    kinds = {}
    for i, v in items:
        if isinstance(v, dict) and "kind" in v and str(i).isascii() and str(i).isdecimal() and int(i) >= 1:
            kinds[int(i)] = str(v["kind"])  # "1.5" failed int() and dropped every kind
    return kinds


def iou_by_kind(per_scene: dict[str, dict], kinds: dict[str, dict[int, str]]
                ) -> dict[str, dict[str, dict[str, float]]]:
    """Mean IoU of the ground-truth bodies of each kind, per track.

    Args:
        per_scene: scene key ``"<track>/<scene>"`` -> :meth:`FrameScores.to_dict` (its
            ``instances``: ``gt`` id and ``IoU`` with the matched prediction, 0 if none).
        kinds: scene key -> :func:`body_kinds` of that scene.

    Returns:
        ``{track: {kind: {"n": bodies, "mIoU": mean IoU}}}``, kinds in name order; tracks
        whose scenes name no kinds are left out.
    """
    sums: dict[str, dict[str, list[float]]] = {}
    for key, scores in per_scene.items():
        named = kinds.get(key) or {}
        track = key.rsplit("/", 1)[0] if "/" in key else key
        for inst in scores.get("instances", []):
            kind = named.get(int(inst["gt"]))
            iou = inst.get("IoU")
            if kind is None or iou is None or math.isnan(iou):
                continue
            sums.setdefault(track, {}).setdefault(kind, []).append(float(iou))
    return {t: {k: {"n": len(v), "mIoU": sum(v) / len(v)} for k, v in sorted(by.items())}
            for t, by in sums.items()}


def format_kinds(results: dict[str, dict]) -> str:
    """Text table of each method's ``by_kind`` block (:func:`iou_by_kind`): one row per
    track and kind, one column per method; ``""`` when no method has one."""
    methods = [m for m, r in results.items() if r.get("by_kind")]
    if not methods:
        return ""
    rows: list[tuple[str, str]] = []
    for m in methods:
        rows += [(t, k) for t, by in results[m]["by_kind"].items() for k in by
                 if (t, k) not in rows]
    width = max(12, *(len(m) for m in methods))
    head = f"{'track':<20}{'kind':<14}{'bodies':>7}" + "".join(f"{m:>{width + 2}}" for m in methods)
    lines = ["[mIoU by kind of body] (meta.json labels)", head, "-" * len(head)]
    for t, k in rows:
        n = next(results[m]["by_kind"][t][k]["n"] for m in methods
                 if k in results[m]["by_kind"].get(t, {}))
        cells = []
        for m in methods:
            entry = results[m]["by_kind"].get(t, {}).get(k)
            text = "-" if entry is None else f"{100 * entry['mIoU']:.1f}"
            cells.append(f"{text:>{width + 2}}")
        lines.append(f"{t:<20}{k:<14}{n:>7}" + "".join(cells))
    return "\n".join(lines) + "\n"
