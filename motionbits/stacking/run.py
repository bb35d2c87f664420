"""Run the tower-stacking table: every method on the same seeded trials (paper Table 3)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path

import numpy as np

from motionbits.frames import whole_number
from motionbits.stacking.trial import (
    FAILURES,
    TrialConfig,
    TrialResult,
    push_scene,
    run_trial,
)
from motionbits.video_writer import H264Writer

__all__ = ["GT", "format_table", "run_stacking", "summarise"]

GT = "gt"  #: method name of the ground-truth masks (the controller's ceiling)


def run_stacking(methods: list[str], trials: int, seed: int, *, config: TrialConfig = TrialConfig(),
                 video_dir: str | Path | None = None,
                 progress: Callable[[str], None] | None = print) -> dict[str, list[TrialResult]]:
    """Run ``trials`` trials of every method (trial ``i`` is the same scene and push for all).

    Args:
        methods: names from :func:`motionbits.baselines.available_methods`, or ``"gt"``.
        trials: number of trials.
        seed: selects the scenes and pushes.
        config: trial parameters.
        video_dir: if given, ``<dir>/<method>_trial<i>.mp4`` of every trial (H.264).
        progress: called with one line per finished trial (None: silent).

    Returns:
        ``{method: [TrialResult, ...]}``.

    Raises:
        KeyError: an unknown method name.
        TypeError: ``methods`` is not a list of names (a str is refused: "gt" read as
            "g", "t"), ``trials`` or ``seed`` not a whole number, ``config`` not a
            :class:`TrialConfig`.
        ValueError: no method, ``trials < 1`` or ``seed < 0``.
    """
    from motionbits.baselines import make_method

    if isinstance(methods, (str, bytes)) or not all(isinstance(m, str) for m in methods):
        raise TypeError(f"methods must be a list of method names, got {methods!r:.60}")
    methods = list(methods)
    if not methods:  # else {}: an empty table
        raise ValueError("methods is empty: name at least one method (or 'gt')")
    if whole_number("trials", trials) < 1:  # True ran 1 trial, 2.5 failed in range()
        raise ValueError(f"--trials must be >= 1, got {trials}")
    trials = int(trials)
    if whole_number("seed", seed) < 0:  # 1.5 ran (seeded with a float), -1 failed in numpy
        raise ValueError(f"seed must be >= 0, got {seed}")
    seed = int(seed)
    if not isinstance(config, TrialConfig):  # else "'dict' object has no attribute 'width'"
        raise TypeError(f"config must be a TrialConfig, got {type(config).__name__}")
    fns = {m: (None if m == GT else make_method(m)) for m in methods}
    results: dict[str, list[TrialResult]] = {m: [] for m in methods}
    for i in range(trials):
        pushed = push_scene(seed, i, config)
        if progress:
            progress(f"trial {i}: push clip {len(pushed.frames)} frames, {pushed.pushed}/5 objects "
                     f"moved, {pushed.seconds:.1f} s")
        for m in methods:
            if video_dir is None:
                r = run_trial(m, fns[m], pushed, config, gt=(m == GT))
            else:
                with H264Writer(Path(video_dir) / f"{m}_trial{i}.mp4", 1.0 / config.frame_dt) as w:
                    r = run_trial(m, fns[m], pushed, config, video=w.write, gt=(m == GT))
            results[m].append(r)
            if progress:
                state = "success" if r.success else f"failed ({r.failure})"
                progress(f"  {m:>14}: {state}, {r.stacked} stacked, {r.n_masks} masks, "
                         f"segmentation {r.segment_seconds:.1f} s, trial {r.seconds:.1f} s")
    return results


def summarise(results: dict[str, list[TrialResult]]) -> dict:
    """The JSON of the issue: ``{"methods": {NAME: {"success": k, "trials": n,
    "stacked_mean": x, "failures": {REASON: count}}}}`` (plus timing)."""
    if not isinstance(results, dict) or not all(
            isinstance(rs, (list, tuple)) and all(isinstance(r, TrialResult) for r in rs)
            for rs in results.values()):  # None: AttributeError 'items'
        raise TypeError(f"results must be a dict of method name -> list of TrialResult "
                        f"(as run_stacking returns), got {results!r:.60}")
    out = {}
    for m, rs in results.items():
        n = len(rs)
        out[m] = {
            "success": int(sum(r.success for r in rs)),
            "trials": n,
            "stacked_mean": float(np.mean([r.stacked for r in rs])) if n else 0.0,
            "stacked_total": int(sum(r.stacked for r in rs)),
            "failures": dict(Counter(r.failure for r in rs if r.failure)),
            "segment_seconds_mean": float(np.mean([r.segment_seconds for r in rs])) if n else 0.0,
            "trial_seconds_mean": float(np.mean([r.seconds for r in rs])) if n else 0.0,
        }
    return {"methods": out}


def format_table(summary: dict) -> str:
    """Table 3's layout: method, # stacked objects (total over trials, and mean), SR,
    failure reasons."""
    keys = ("success", "trials", "stacked_mean", "stacked_total", "failures")
    if not (isinstance(summary, dict) and isinstance(summary.get("methods"), dict) and all(
            isinstance(s, dict) and all(k in s for k in keys) for s in summary["methods"].values())):
        raise TypeError(f"summary must be a dict as summarise returns ({{'methods': {{NAME: "
                        f"{{{', '.join(keys)}}}}}}}), got {summary!r:.60}")  # {}: KeyError 'methods'
    for m, s in summary["methods"].items():  # else ValueError "'timeout' is not in tuple" from FAILURES.index
        fails = s["failures"]
        if not isinstance(fails, dict) or not all(k in FAILURES for k in fails):
            raise ValueError(f"summary['methods'][{m!r}]['failures'] must map failure reasons "
                             f"({', '.join(FAILURES)}) to counts, got {fails!r:.60}")
    rows = [("Method", "# Stacked Objs", "SR", "Failures")]
    for m, s in summary["methods"].items():
        fails = ", ".join(f"{k} {v}" for k, v in sorted(s["failures"].items(),
                                                         key=lambda kv: FAILURES.index(kv[0])))
        rows.append((m, f"{s['stacked_total']} ({s['stacked_mean']:.1f}/trial)",
                     f"{s['success']} / {s['trials']}", fails or "-"))
    widths = [max(len(r[c]) for r in rows) for c in range(4)]
    lines = ["  ".join(v.ljust(w) for v, w in zip(r, widths)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
