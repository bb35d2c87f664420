"""Two scored runs on the same scenes, compared: paired per-body differences with a
bootstrap confidence interval over scenes (ours).

One change to a segmenter moves some scenes' scores a lot either way (a body's mark found
or lost at the last frame moves its scene's mIoU by tens of points), so the difference of
two tracks' means says little by itself. Here the same GT bodies are paired across the
two runs, and the interval comes from resampling the *scenes* with replacement (the
bodies of one scene are not independent): a difference whose interval holds 0 is not
shown by these scenes.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["compare_runs", "format_comparison", "scene_changes", "format_scene_changes",
           "ALL_TRACKS", "BOOTSTRAP_SAMPLES", "SCENE_CHANGE"]

#: Bootstrap resamples of the scenes.
BOOTSTRAP_SAMPLES = 5000
#: The row of every scene of every track (where the runs hold several tracks).
ALL_TRACKS = "all tracks"
#: A scene counts as up or down where its bodies' mean IoU changed by more than this.
SCENE_CHANGE = 0.005


class _Scene(NamedTuple):
    """One scene of both runs: its key, its GT ids (n,), the IoUs of run a and of run b
    (n,) in that order, and the spurious marks of each."""

    key: str
    gts: np.ndarray
    a: np.ndarray
    b: np.ndarray
    spurious_a: float
    spurious_b: float


def _paired(a: dict, b: dict) -> dict[str, list[_Scene]]:
    """Per track, its scenes in both runs (:class:`_Scene`), in key order."""
    if set(a) != set(b):
        only = sorted(set(a) ^ set(b))
        raise ValueError(f"the two runs are not on the same scenes ({len(only)} scenes in one "
                         f"only, e.g. {only[0]})")
    tracks: dict[str, list[_Scene]] = {}
    for key in sorted(a):
        ia = {i["gt"]: i["IoU"] for i in a[key]["instances"]}
        ib = {i["gt"]: i["IoU"] for i in b[key]["instances"]}
        if set(ia) != set(ib):
            raise ValueError(f"scene {key}: the two runs score different GT bodies "
                             f"({sorted(ia)} vs {sorted(ib)}): not the same ground truth")
        gts = sorted(ia)
        track = key.rsplit("/", 1)[0] if "/" in key else ""
        tracks.setdefault(track, []).append(_Scene(
            key, np.array(gts, int), np.array([ia[g] for g in gts], float),
            np.array([ib[g] for g in gts], float),
            a[key]["false_positives"]["spurious"], b[key]["false_positives"]["spurious"]))
    return tracks


def compare_runs(a: dict, b: dict, *, level: float = 0.95, samples: int = BOOTSTRAP_SAMPLES,
                 seed: int = 0) -> dict[str, dict]:
    """Per track, the change of mIoU (mean IoU over GT bodies) from run ``a`` to run ``b``.

    Args:
        a, b: the ``per_scene`` dicts of two runs (``motionbits benchmark --json`` or
            ``motionbits eval --json``: ``{"track/scene": {"instances": [{"gt", "IoU"}, ...],
            "false_positives": {...}}}``) on the same scenes and ground truth.
        level: of the confidence interval, in (0, 1).
        samples: bootstrap resamples of the scenes.
        seed: of the resampling (the interval is reproducible).

    Returns:
        ``{track: {"scenes", "instances", "mIoU_a", "mIoU_b", "delta", "ci": (low, high),
        "up", "down", "spurious_a", "spurious_b"}}``: IoUs as fractions; ``up`` / ``down``
        count the scenes whose bodies' mean IoU changed by more than ``SCENE_CHANGE``;
        spurious marks are the mean per scene. Tracks without a GT body are left out;
        where the runs hold several tracks, ``ALL_TRACKS`` pools their scenes.

    Raises:
        ValueError: the runs cover different scenes or bodies, or ``level`` is not in (0, 1).
    """
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    rng = np.random.default_rng(seed)
    paired = _paired(a, b)
    groups = dict(paired)
    if len(paired) > 1:  # every scene of every track, resampled together
        groups[ALL_TRACKS] = [s for scenes in paired.values() for s in scenes]
    out = {}
    for track, scenes in groups.items():
        summary = _summarize(scenes, rng, level, samples)
        if summary is not None:
            out[track] = summary
    return out


def _summarize(scenes: list[_Scene], rng: np.random.Generator, level: float,
               samples: int) -> dict | None:
    """One row of :func:`compare_runs` (None: no GT body in these scenes)."""
    spurious_a = float(np.mean([s.spurious_a for s in scenes]))
    spurious_b = float(np.mean([s.spurious_b for s in scenes]))
    scenes = [s for s in scenes if s.a.size]
    if not scenes:
        return None
    n = np.array([s.a.size for s in scenes], float)
    sum_a = np.array([s.a.sum() for s in scenes])
    diff = np.array([(s.b - s.a).sum() for s in scenes])
    pick = rng.integers(0, len(scenes), (samples, len(scenes)))
    boot = diff[pick].sum(axis=1) / n[pick].sum(axis=1)
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(boot, [tail, 100 - tail])
    per_scene = diff / n
    return {
        "scenes": len(scenes), "instances": int(n.sum()),
        "mIoU_a": float(sum_a.sum() / n.sum()), "mIoU_b": float((sum_a + diff).sum() / n.sum()),
        "delta": float(diff.sum() / n.sum()), "ci": (float(low), float(high)),
        "up": int((per_scene > SCENE_CHANGE).sum()),
        "down": int((per_scene < -SCENE_CHANGE).sum()),
        "spurious_a": spurious_a, "spurious_b": spurious_b,
    }


def format_comparison(result: dict[str, dict], names: tuple[str, str] = ("A", "B"),
                      level: float = 0.95) -> str:
    """One line per track of :func:`compare_runs`' result, IoUs in %."""
    a, b = names
    head = (f"{'track':<24}{'scenes':>7}{'bodies':>7}{'mIoU ' + a:>12}{'mIoU ' + b:>12}"
            f"{'delta':>8}  {f'{100 * level:.0f}% CI':<16}{'up':>4}{'down':>5}"
            f"{'Spur ' + a:>10}{'Spur ' + b:>10}")
    lines = [head, "-" * len(head)]
    for track, r in result.items():
        lo, hi = r["ci"]
        lines.append(
            f"{track or '.':<24}{r['scenes']:>7}{r['instances']:>7}{100 * r['mIoU_a']:>12.1f}"
            f"{100 * r['mIoU_b']:>12.1f}{100 * r['delta']:>+8.1f}  "
            f"{f'[{100 * lo:+.1f}, {100 * hi:+.1f}]':<16}{r['up']:>4}{r['down']:>5}"
            f"{r['spurious_a']:>10.2f}{r['spurious_b']:>10.2f}")
    lines.append(f"delta: mIoU {b} - {a} over the same GT bodies; CI: bootstrap over scenes; "
                 f"up / down: scenes whose bodies' mean IoU moved by more than "
                 f"{100 * SCENE_CHANGE:.1f} points")
    return "\n".join(lines) + "\n"


def scene_changes(a: dict, b: dict) -> list[dict]:
    """The scenes of two runs on the same scenes, the largest change of their bodies'
    mean IoU first (where a change came from: a body found or lost).

    Args:
        a, b: ``per_scene`` dicts as for :func:`compare_runs`.

    Returns:
        One dict per scene with a GT body: ``{"scene", "mIoU_a", "mIoU_b", "delta",
        "bodies": [(gt id, IoU a, IoU b), ...], "spurious_a", "spurious_b"}`` (IoUs as
        fractions); ties keep the key order.

    Raises:
        ValueError: the runs cover different scenes or bodies.
    """
    rows = [{"scene": s.key, "mIoU_a": float(s.a.mean()), "mIoU_b": float(s.b.mean()),
             "delta": float((s.b - s.a).mean()),
             "bodies": [(int(g), float(x), float(y)) for g, x, y in zip(s.gts, s.a, s.b)],
             "spurious_a": s.spurious_a, "spurious_b": s.spurious_b}
            for scenes in _paired(a, b).values() for s in scenes if s.a.size]
    return sorted(rows, key=lambda r: -abs(r["delta"]))


def format_scene_changes(rows: list[dict], names: tuple[str, str] = ("A", "B")) -> str:
    """One line per scene of :func:`scene_changes`' result (IoUs in %; each body's IoU in
    A -> B where it changed in the two decimals shown)."""
    a, b = names
    width = max([len("scene")] + [len(r["scene"]) for r in rows]) + 2
    head = (f"{'scene':<{width}}{'mIoU ' + a:>9}{'mIoU ' + b:>9}{'delta':>8}"
            f"{'Spur ' + a:>8}{'Spur ' + b:>8}  bodies whose IoU changed ({a} -> {b})")
    lines = [head, "-" * len(head)]
    for r in rows:
        moved = "  ".join(f"{g}: {x:.2f} -> {y:.2f}" for g, x, y in r["bodies"]
                          if f"{x:.2f}" != f"{y:.2f}")
        lines.append(f"{r['scene']:<{width}}{100 * r['mIoU_a']:>9.1f}{100 * r['mIoU_b']:>9.1f}"
                     f"{100 * r['delta']:>+8.1f}{r['spurious_a']:>8g}{r['spurious_b']:>8g}  "
                     f"{moved or '-'}")
    return "\n".join(lines) + "\n"
