"""``motionbits compare``: is run B better than run A on the same scenes, beyond chance?"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from motionbits.outputs import check_output_file, write_text_atomic

__all__ = ["register", "run", "load_run"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "compare",
        help="compare two scored runs on the same scenes (paired, with a bootstrap CI)",
        description=(
            "Per track, the change of mIoU from run A to run B over the same GT bodies, a "
            "bootstrap confidence interval over scenes, and how many scenes went up or down. "
            "A and B are --json files of 'motionbits benchmark' or 'motionbits eval'."
        ),
    )
    p.add_argument("a", metavar="A.json", help="the reference run")
    p.add_argument("b", metavar="B.json", help="the run compared with it")
    p.add_argument("--method", metavar="NAME",
                   help="the method to compare where a file holds several (benchmark runs); "
                        "default: the only one")
    p.add_argument("--level", type=float, default=0.95,
                   help="confidence level of the interval (default 0.95)")
    p.add_argument("--scenes", type=int, default=0, metavar="N",
                   help="also list the N scenes whose mIoU changed most, with the bodies "
                        "that changed (default 0: none)")
    p.add_argument("--json", metavar="FILE", help="write the comparison here")
    p.set_defaults(func=run)
    return p


def load_run(path: str | Path, method: str | None = None) -> dict:
    """The ``per_scene`` dict of one method in a ``benchmark`` / ``eval`` --json file (a
    file of one run, ``eval`` of one prediction folder, needs no ``method``).

    Raises:
        FileNotFoundError: no such file.
        ValueError: not such a file, or ``method`` is missing from it or needed to choose.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:  # else "'utf-8' codec can't decode byte ..." (which file?)
        raise ValueError(f"{path} is not a text file (not UTF-8): not a --json file of "
                         "motionbits benchmark or eval") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not JSON: {exc}") from exc
    if not isinstance(data, dict):
        raise ValueError(f"{path} is not a --json file of motionbits benchmark or eval")
    if "per_scene" in data:  # eval --json of one prediction folder: ``method`` is moot
        return _scored(path, data["per_scene"])
    methods = data.get("methods")
    if not isinstance(methods, dict) or not methods:
        raise ValueError(f"{path} is not a --json file of motionbits benchmark or eval "
                         "(no 'per_scene' or 'methods')")
    if method is None:
        if len(methods) > 1:
            raise ValueError(f"{path} holds several methods ({', '.join(methods)}); "
                             "choose one with --method")
        method = next(iter(methods))
    if method not in methods:
        raise ValueError(f"{path} has no method {method!r} (it has {', '.join(methods)})")
    entry = methods[method]
    return _scored(path, entry.get("per_scene") if isinstance(entry, dict) else None, method)


def _scored(path: Path, per_scene, method: str | None = None) -> dict:
    """``per_scene`` if it is scores of scenes (``{scene: {"instances": [{"gt", "IoU"}],
    "false_positives": {"spurious"}}}``); else ValueError naming ``path``."""
    def scene_ok(v) -> bool:
        return (isinstance(v, dict) and isinstance(v.get("instances"), list)
                and all(isinstance(i, dict) and "gt" in i and "IoU" in i for i in v["instances"])
                and isinstance(v.get("false_positives"), dict) and "spurious" in v["false_positives"])

    where = f"{path}" if method is None else f"{path} method {method!r}"
    if not isinstance(per_scene, dict):
        raise ValueError(f"{where} has no 'per_scene' scores: not a --json file of motionbits "
                         "benchmark or eval")
    bad = next((k for k, v in per_scene.items() if not scene_ok(v)), None)
    if bad is not None:
        raise ValueError(f"{where}: scene {bad!r} is not scored (no 'instances' of gt/IoU and "
                         "'false_positives'): not a --json file of motionbits benchmark or eval")
    for key, v in per_scene.items():  # the values too: null read as NaN, 7 as 700%
        for i in v["instances"]:
            if not _is_number(i["IoU"]) or not 0 <= i["IoU"] <= 1:
                raise ValueError(f"{where}: scene {key!r} body {i['gt']!r} has IoU "
                                 f"{i['IoU']!r:.40}; an IoU is a number in [0, 1]")
        spurious = v["false_positives"]["spurious"]
        if not _is_number(spurious) or spurious < 0:
            raise ValueError(f"{where}: scene {key!r} has spurious {spurious!r:.40}; it is a "
                             "count of predicted objects, a number >= 0")
    return per_scene


def _is_number(value) -> bool:
    """A finite int or float, not a bool (JSON's true) nor a str."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))


def run(args: argparse.Namespace) -> int:
    from motionbits.eval.compare import (compare_runs, format_comparison,
                                         format_scene_changes, scene_changes)
    from motionbits.eval.losses import format_losses, loss_budget
    from motionbits.eval.table import json_ready

    if not 0.0 < args.level < 1.0:  # else the library's message names ``level``
        raise ValueError(f"--level must be in (0, 1), got {args.level:g}")
    if args.scenes < 0:
        raise ValueError(f"--scenes must be >= 0, got {args.scenes}")
    if args.json is not None:
        check_output_file(args.json, "--json")
    a, b = load_run(args.a, args.method), load_run(args.b, args.method)
    result = compare_runs(a, b, level=args.level)
    if not result:
        raise ValueError("no track of these runs has a GT body to compare")
    print(format_comparison(result, names=("A", "B"), level=args.level), end="")
    saved = {"a": str(args.a), "b": str(args.b), "level": args.level, "tracks": result}
    # where each run's points go (runs saved before the marks' P and R were kept: not shown)
    if all("P" in i and "R" in i for run in (a, b) for v in run.values() for i in v["instances"]):
        saved["losses"] = {"A": loss_budget(a), "B": loss_budget(b)}
        print()
        print(format_losses({n: {"losses": v} for n, v in saved["losses"].items()}), end="")
    if args.scenes:
        moved = scene_changes(a, b)[:args.scenes]
        print(f"\nthe {len(moved)} scenes that changed most:")
        print(format_scene_changes(moved), end="")
        saved["scenes"] = moved
    if args.json is not None:
        write_text_atomic(args.json, json.dumps(json_ready(saved), indent=1, allow_nan=False))
    return 0
