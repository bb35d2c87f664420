"""The paper's Table 2 layout: rows = methods, Overlap P R F1 mIoU and Boundary P R F1 in %,
then the false positives: static FP in % (pooled over the scenes' pixels) and spurious
MotionBits (mean per scene)."""

from __future__ import annotations

import math

__all__ = ["format_table", "json_ready"]

_COLS = ("P", "R", "F1", "mIoU", "BP", "BR", "BF1")
_LEGEND = ("sFP: % of the static pixels (GT background, not ignored) inside a predicted object, "
           "pooled over a track's scenes\nSpur: predicted objects matched to no GT object, mean "
           "per scene (track averages: mean over tracks)")


def _missing(v: float | None) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def _pct(v: float | None) -> str:
    return "-" if _missing(v) else f"{100 * v:.1f}"


def _num(v: float | None) -> str:
    return "-" if _missing(v) else f"{v:.1f}"


def format_table(
    results: dict[str, dict],
    *,
    block: str = "macro",
    seconds_per_frame: dict[str, float] | None = None,
) -> str:
    """Render per-track and track-averaged tables for several methods.

    Args:
        results: ``{method: evaluate_dataset(...) result}`` (its ``false_positives`` block
            gives the last two columns: ``static_fp`` in %, ``spurious`` per scene).
        block: ``"macro"`` (the paper's numbers) or ``"pooled"`` (UOIS variant; adds %75).
        seconds_per_frame: optional ``{method: s}``, printed as a last column.

    Returns:
        The table as text, one section per track and one "average over tracks".
    """
    if not results:
        raise ValueError("no results to tabulate")
    cols = _COLS + (("pct75",) if block == "pooled" else ())
    heads = ["P", "R", "F1", "mIoU", "P", "R", "F1"] + (["%75"] if block == "pooled" else [])
    heads += ["sFP", "Spur"]
    name_w = max(12, *(len(m) for m in results))
    timing = seconds_per_frame or {}
    time_head = "  s/frame" if timing else ""
    lines = []
    group = (" " * (name_w + 2) + f"{'Overlap':^28}" + f"{'Boundary':^21}"
             + " " * (7 if block == "pooled" else 0) + f"{'False pos.':^14}").rstrip()
    header = f"{'Method':<{name_w}}  " + "".join(f"{h:>7}" for h in heads) + time_head
    tracks: list[str] = []
    for res in results.values():
        tracks += [t for t in res["tracks"] if t not in tracks]
    sections = [(t, lambda r, t=t: r["tracks"].get(t)) for t in tracks]
    if len(tracks) > 1:
        sections.append(("average over tracks", lambda r: r))
    for title, pick in sections:
        counts = ""
        if title in tracks:
            first = next(r for r in results.values() if title in r["tracks"])["tracks"][title]
            counts = f" ({first['n_images']} scenes, {first['n_instances']} GT instances)"
        lines += [f"[{block}] {title}{counts}", group, header, "-" * len(header)]
        for method, res in results.items():
            summary = pick(res) or {}
            vals, fp = summary.get(block, {}), summary.get("false_positives", {})
            row = f"{method:<{name_w}}  " + "".join(f"{_pct(vals.get(c)):>7}" for c in cols)
            row += f"{_pct(fp.get('static_fp')):>7}{_num(fp.get('spurious')):>7}"
            if timing:
                t = timing.get(method)
                row += f"{t:>9.3f}" if t is not None else f"{'-':>9}"
            lines.append(row)
        lines.append("")
    lines.append(_LEGEND)
    return "\n".join(lines).rstrip() + "\n"


def json_ready(obj):
    """Copy of nested dicts/lists with NaN floats replaced by None (strict JSON)."""
    if isinstance(obj, dict):
        return {k: json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, float) and math.isnan(obj):
        return None
    return obj
