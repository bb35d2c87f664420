"""Mean IoU per kind and per role of body: which bodies a method misses.

A track's mIoU mixes the agent (a gripper or hand, large and always moving) with the bodies
it moves; a drop on laptop lids or glued composites hides in it. Scenes made by
``motionbits synth`` name each ground-truth body's kind in ``meta.json``
(``{"labels": {"1": {"kind": "laptop", "body": "obj5", ...}, ...}}``) and what the agents
did to which body (``"script"``: ``carries``, ``kicks``; ``"push"``: the target), so that
a body's *role* is known too: the agent (where it is scored), carried (grasped, lifted,
set down), knocked (kicked), pushed (the push target, not carried) or other (moved by a
collision). Scenes without them are left out.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

__all__ = ["body_kinds", "body_roles", "body_kinds_and_roles", "iou_by_kind",
           "format_kinds", "format_breakdowns", "scene_track", "AGENT_KINDS"]

#: Kinds of the agents of ``motionbits synth`` (a gripper or hand scored as a body).
AGENT_KINDS = frozenset({"gripper", "hand", "pusher"})


def _meta(scene: str | Path) -> dict:
    """A scene's ``meta.json`` as a dict, ``{}`` when it is missing, not JSON, or not an
    object."""
    try:
        meta = json.loads((Path(scene) / "meta.json").read_text())
    except (OSError, ValueError, RecursionError):
        return {}  # RecursionError: brackets nested thousands deep
    return meta if isinstance(meta, dict) else {}


def _labels(meta: dict) -> dict[int, dict]:
    """Ground-truth id -> its entry in ``meta["labels"]``; entries that are not objects and
    ids that are not whole numbers >= 1 are skipped (not the scene's every label)."""
    labels = meta.get("labels")
    if not isinstance(labels, dict):
        return {}
    return {int(i): v for i, v in labels.items()
            if isinstance(v, dict) and str(i).isascii() and str(i).isdecimal() and int(i) >= 1}


def body_kinds(scene: str | Path) -> dict[int, str]:
    """Ground-truth id -> kind of body, from a scene's ``meta.json`` (``labels.<id>.kind``).

    Returns ``{}`` when the scene has no ``meta.json``, it is not JSON, or it names no
    kinds (``meta.json`` is free-form; a DAVIS window has none). An entry whose id is not
    a whole number >= 1 is skipped, not the scene's every kind.
    """
    return _kinds(_meta(scene))


def body_roles(scene: str | Path) -> dict[int, str]:
    """Ground-truth id -> role of the body, from a scene's ``meta.json``, the first that
    holds of: ``agent`` if its kind is an agent's (:data:`AGENT_KINDS`; the robot and hand
    tracks score the agent), ``carried`` if an agent carried it (``script.carries[].body``),
    ``knocked`` if it was kicked (``script.kicks[].body``), ``pushed`` if it is the push
    target (``push.target``), else ``other``.

    Returns ``{}`` when the scene names no bodies (``labels.<id>.body``) or says nothing of
    what the agents did (no ``script`` and no ``push``): its roles are not known.
    """
    return _roles(_meta(scene))


def body_kinds_and_roles(scene: str | Path) -> tuple[dict[int, str], dict[int, str]]:
    """:func:`body_kinds` and :func:`body_roles` of a scene, reading its ``meta.json``
    once."""
    meta = _meta(scene)
    return _kinds(meta), _roles(meta)


def _kinds(meta: dict) -> dict[int, str]:
    return {i: str(v["kind"]) for i, v in _labels(meta).items() if "kind" in v}


def _roles(meta: dict) -> dict[int, str]:
    script, push = meta.get("script"), meta.get("push")
    if not isinstance(script, dict) and not isinstance(push, dict):
        return {}

    def bodies(key: str) -> set[str]:
        items = script.get(key) if isinstance(script, dict) else None
        return {str(e["body"]) for e in items if isinstance(e, dict) and "body" in e} \
            if isinstance(items, list) else set()

    carried, knocked = bodies("carries"), bodies("kicks")
    pushed = str(push["target"]) if isinstance(push, dict) and "target" in push else None
    roles = {}
    for i, v in _labels(meta).items():
        if "body" not in v:
            continue
        body = str(v["body"])
        roles[i] = ("agent" if v.get("kind") in AGENT_KINDS
                    else "carried" if body in carried else "knocked" if body in knocked
                    else "pushed" if body == pushed else "other")
    return roles


def scene_track(key: str) -> str:
    """The track of a scene key ``"<track>/<scene>"`` (a key without a track: itself)."""
    return key.rsplit("/", 1)[0] if "/" in key else key


def iou_by_kind(per_scene: dict[str, dict], kinds: dict[str, dict[int, str]]
                ) -> dict[str, dict[str, dict[str, float]]]:
    """Mean IoU of the ground-truth bodies of each kind (or role), per track, and the share
    of them missed (IoU 0: no prediction matched).

    Args:
        per_scene: scene key ``"<track>/<scene>"`` -> :meth:`FrameScores.to_dict` (its
            ``instances``: ``gt`` id and ``IoU`` with the matched prediction, 0 if none).
        kinds: scene key -> :func:`body_kinds` (or :func:`body_roles`) of that scene.

    Returns:
        ``{track: {kind: {"n": bodies, "mIoU": mean IoU, "missed": share with IoU 0}}}``,
        kinds in name order; tracks whose scenes name no kinds are left out.
    """
    sums: dict[str, dict[str, list[float]]] = {}
    for key, scores in per_scene.items():
        named = kinds.get(key) or {}
        track = scene_track(key)
        for inst in scores.get("instances", []):
            kind = named.get(int(inst["gt"]))
            iou = inst.get("IoU")
            if kind is None or iou is None or math.isnan(iou):
                continue
            sums.setdefault(track, {}).setdefault(kind, []).append(float(iou))
    return {t: {k: {"n": len(v), "mIoU": sum(v) / len(v),
                    "missed": sum(x == 0.0 for x in v) / len(v)}
                for k, v in sorted(by.items())}
            for t, by in sums.items()}


_TABLES = {"by_kind": ("kind", "[mIoU by kind of body] (meta.json labels)"),
           "by_role": ("role", "[mIoU by role of body] (meta.json script: agent, carried, "
                               "knocked, pushed, other)")}


def format_kinds(results: dict[str, dict], block: str = "by_kind") -> str:
    """Text table of each method's ``block`` (``"by_kind"`` or ``"by_role"``,
    :func:`iou_by_kind`): one row per track and kind, one column per method, each cell
    "mIoU (% of the bodies missed)"; ``""`` when no method has one."""
    column, title = _TABLES[block]
    methods = [m for m, r in results.items() if r.get(block)]
    if not methods:
        return ""
    rows: list[tuple[str, str]] = []
    for m in methods:
        rows += [(t, k) for t, by in results[m][block].items() for k in by
                 if (t, k) not in rows]
    width = max(14, *(len(m) for m in methods))
    head = f"{'track':<20}{column:<14}{'bodies':>7}" + "".join(f"{m:>{width + 2}}" for m in methods)
    lines = [title + ", mIoU (% missed)", head, "-" * len(head)]
    for t, k in rows:
        n = next(results[m][block][t][k]["n"] for m in methods
                 if k in results[m][block].get(t, {}))
        cells = []
        for m in methods:
            entry = results[m][block].get(t, {}).get(k)
            text = ("-" if entry is None else
                    f"{100 * entry['mIoU']:.1f} ({100 * entry.get('missed', 0.0):.0f}%)")
            cells.append(f"{text:>{width + 2}}")
        lines.append(f"{t:<20}{k:<14}{n:>7}" + "".join(cells))
    return "\n".join(lines) + "\n"


def format_breakdowns(results: dict[str, dict]) -> str:
    """The tables of :func:`format_kinds` that the results have (kinds, then roles), a
    blank line between them; ``""`` when none."""
    return "\n".join(t for t in (format_kinds(results, b) for b in _TABLES) if t)
