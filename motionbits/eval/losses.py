"""Where the mIoU points go: each body's loss by how its mark fails.

A track's mIoU is the mean IoU of its ground-truth bodies, so ``100 - mIoU`` is the mean of
``100 * (1 - IoU)`` over them. Splitting that loss by how each body's matched mark fails
tells which kind of fix is worth the most before any is tried:

- ``missed``: no mark matched the body (IoU 0);
- ``short``: the mark lies within the body (precision >= ``SIDE``) but covers too little
  of it (a face left out, a body split among marks);
- ``spill``: the mark covers the body (recall >= ``SIDE``) and more (a cast shadow, the
  table around it, a neighbour);
- ``both``: neither -- the mark covers part of the body and part of something else;
- ``close``: IoU >= ``CLOSE`` (what is left is the outline's few pixels).

The five sum to ``100 - mIoU``. Bodies whose IoU is undefined (NaN) are left out, as
:func:`motionbits.eval.kinds.iou_by_kind` leaves them out.
"""

from __future__ import annotations

import math

from motionbits.eval.kinds import scene_track

__all__ = ["FAILURES", "CLOSE", "SIDE", "failure", "loss_budget", "format_losses"]

#: How a body's mark fails, in the order the tables show them.
FAILURES = ("missed", "short", "spill", "both", "close")
#: A body whose mark reaches this IoU is ``close``.
CLOSE = 0.8
#: A mark is ``short`` of its body at this precision or more, ``spill`` at this recall or
#: more (both: the larger of the two decides).
SIDE = 0.8


def failure(iou: float, precision: float, recall: float) -> str:
    """How a body's matched mark fails (one of :data:`FAILURES`), from its IoU and the
    mark's precision and recall on the body (all in [0, 1]; 0 when nothing matched)."""
    if iou <= 0.0:
        return "missed"
    if iou >= CLOSE:
        return "close"
    if precision >= SIDE or recall >= SIDE:
        return "short" if precision >= recall else "spill"
    return "both"


def loss_budget(per_scene: dict[str, dict]) -> dict[str, dict[str, float]]:
    """Each track's ``100 - mIoU`` split by :func:`failure`.

    Args:
        per_scene: scene key ``"<track>/<scene>"`` -> :meth:`FrameScores.to_dict` (its
            ``instances``: ``IoU``, ``P`` and ``R`` of each ground-truth body's matched
            mark, 0 when none).

    Returns:
        ``{track: {"n": bodies, "mIoU": mean IoU x 100, "missed": points, "short": ...,
        "close": points}}``; the points of a track sum to ``100 - mIoU``. Tracks without
        a body are left out.
    """
    bodies: dict[str, list[tuple[str, float]]] = {}  # track -> (failure, loss) per body
    for key, scores in per_scene.items():
        for inst in scores.get("instances", []):
            iou = inst.get("IoU")
            if iou is None or math.isnan(iou):
                continue
            kind = failure(float(iou), float(inst.get("P", 0.0)), float(inst.get("R", 0.0)))
            bodies.setdefault(scene_track(key), []).append((kind, 100.0 * (1.0 - float(iou))))
    out = {}
    for track, rows in bodies.items():
        points = dict.fromkeys(FAILURES, 0.0)
        for kind, loss in rows:
            points[kind] += loss / len(rows)
        out[track] = {"n": len(rows), "mIoU": 100.0 - sum(points.values()), **points}
    return out


def format_losses(results: dict[str, dict]) -> str:
    """Text table of each method's ``losses`` (:func:`loss_budget`): one row per track and
    method; ``""`` when no method has one."""
    rows = [(t, m, entry) for m, r in results.items() for t, entry in r.get("losses", {}).items()]
    if not rows:
        return ""
    width = max(12, *(len(m) for _, m, _ in rows))
    head = (f"{'track':<20}{'method':<{width + 2}}{'bodies':>7}{'mIoU':>7}"
            + "".join(f"{k:>8}" for k in FAILURES))
    lines = ["[where the mIoU points go] 100 - mIoU by how each body's mark fails, points",
             head, "-" * len(head)]
    for t, m, entry in sorted(rows, key=lambda r: r[0]):
        lines.append(f"{t:<20}{m:<{width + 2}}{entry['n']:>7}{entry['mIoU']:>7.1f}"
                     + "".join(f"{entry[k]:>8.1f}" for k in FAILURES))
    lines += ["", f"missed: no mark matched; short: precision >= {SIDE:g}; spill: recall >= "
                  f"{SIDE:g}; both: neither; close: IoU >= {CLOSE:g}"]
    return "\n".join(lines) + "\n"
