"""``motionbits benchmark``: run methods over a MoRiBo dataset and print the Table 2 layout."""

from __future__ import annotations

import argparse
import json
from contextlib import nullcontext

from motionbits.errors import InputError
from motionbits.outputs import StagedFolder, check_output_file, write_text_atomic

__all__ = ["register", "run", "parse_method_options"]

_OPTION_HELP = ("keyword option for the factory of a method in --methods (repeatable); the value "
                "is a string, the method converts it; see the example below")

_EPILOG = """\
example: the VLM -> YOLOE baseline (a plug-in from vlm_adapters; options in docs/vlm_adapters.md)
  motionbits benchmark --data DIR --methods motionbits vlm-yoloe \\
    --option vlm-yoloe.vlm=qwen2.5-vl:/models/Qwen2.5-VL-7B-Instruct \\
    --option vlm-yoloe.yoloe=/models/yoloe-11l-seg.pt \\
    --option vlm-yoloe.text_encoder=/models/mobileclip_blt.ts
"""


def parse_method_options(items: list[str] | None, methods: list[str],
                         known: list[str] | None = None) -> dict[str, dict[str, str]]:
    """``["vlm-yoloe.vlm=stub:x", ...]`` -> ``{"vlm-yoloe": {"vlm": "stub:x"}, ...}``.

    The method name is what comes before the last ``.`` left of the first ``=``; the value
    is everything after that ``=`` (it may contain ``=``, ``.`` and ``:``).

    Raises:
        ValueError: malformed item, a key given twice, an unknown method (not in ``known``,
            when given) or a method not in ``methods``.
    """
    out: dict[str, dict[str, str]] = {}
    for item in items or []:
        target, eq, value = item.partition("=")
        method, dot, key = target.rpartition(".")
        if not eq or not dot or not method or not key.isidentifier():
            raise ValueError(f"--option {item!r}: expected METHOD.KEY=VALUE, e.g. vlm-yoloe.yoloe=/models/yoloe-11l-seg.pt")
        if known is not None and method not in known:
            raise ValueError(f"--option {item!r}: unknown method {method!r}; available: {', '.join(known)}")
        if method not in methods:
            raise ValueError(f"--option {item!r}: method {method!r} is not in --methods ({' '.join(methods)})")
        opts = out.setdefault(method, {})
        if key in opts:
            raise ValueError(f"--option {item!r}: {method}.{key} is given twice")
        opts[key] = value
    return out


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "benchmark",
        help="ACCURACY of methods: run them on MoRiBo-format data and score them (speed: see bench)",
        description=(
            "Run each method on every scene (frames -> last-frame label map), score it with the\n"
            "MoRiBo protocol (see 'motionbits eval') and print Overlap / Boundary P R F1 (mIoU)\n"
            "per track and averaged over tracks, with seconds per frame; on scenes whose meta.json\n"
            "names each body's kind (motionbits synth), also the mean IoU per kind of body."
        ),
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--data", metavar="DIR",
                   help="MoRiBo scene, track (folder of scenes) or folder of tracks (required unless --list)")
    p.add_argument("--methods", nargs="+", default=["flow-cc", "affine-ransac", "motionbits"],
                   metavar="NAME", help="registered methods (default: flow-cc affine-ransac "
                                        "motionbits; --list shows all)")
    p.add_argument("--option", action="append", default=[], metavar="METHOD.KEY=VALUE", help=_OPTION_HELP)
    p.add_argument("--list", action="store_true", help="list the registered methods and exit")
    p.add_argument("--json", metavar="FILE", help="write all scores and timings here")
    p.add_argument("--save-pred", metavar="DIR", help="write predictions as DIR/<method>/<track>/<scene>.png")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing --save-pred folder of an earlier run (default: refuse)")
    p.add_argument("--max-scenes", type=int, metavar="N", help="only the first N scenes per track")
    p.add_argument("--pooled", action="store_true", help="also print the pooled (UOIS) table")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from motionbits.baselines import available_methods, make_method
    from motionbits.eval.benchmark import run_benchmark
    from motionbits.eval.kinds import format_breakdowns
    from motionbits.eval.losses import format_losses
    from motionbits.eval.table import format_table, json_ready

    if args.list:
        for name, desc in available_methods().items():
            print(f"{name:<16} {desc}")
        return 0
    if not args.data:
        raise ValueError("--data DIR is required (unless --list)")
    known = available_methods()
    unknown = [m for m in args.methods if m not in known]
    if unknown:
        raise ValueError(f"unknown method(s) {', '.join(unknown)}; available: {', '.join(known)}")
    names = list(dict.fromkeys(args.methods))
    options = parse_method_options(args.option, names, list(known))
    if args.max_scenes is not None and args.max_scenes < 1:
        raise InputError(f"--max-scenes must be >= 1, got {args.max_scenes}")
    methods = {}
    for name in names:
        try:
            methods[name] = make_method(name, **options.get(name, {}))
        except (ImportError, TypeError, ValueError, KeyError) as exc:
            # a plug-in's optional dependency (the message names the extra), an unknown
            # option or a value of the wrong type: all before any scene is run
            raise InputError(f"method {name!r} cannot be built: {exc}") from exc
    if args.json is not None:
        check_output_file(args.json, "--json")
    save = args.save_pred is not None  # "" is refused, not skipped
    staged = (StagedFolder(args.save_pred, overwrite=args.overwrite, option="--save-pred",
                           replaceable=set(known)) if save else nullcontext())
    with staged:  # predictions appear at --save-pred only if the whole run succeeded
        results, spf = run_benchmark(args.data, methods, save_pred=staged.path if save else None,
                                     max_scenes=args.max_scenes, progress=not args.quiet)
        if save:
            staged.publish()
    print(format_table(results, block="macro", seconds_per_frame=spf), end="")
    if args.pooled:
        print()
        print(format_table(results, block="pooled", seconds_per_frame=spf), end="")
    losses = format_losses(results)
    if losses:  # every scored body, by how its mark fails
        print()
        print(losses, end="")
    breakdowns = format_breakdowns(results)
    if breakdowns:  # scenes of motionbits synth name their bodies' kinds and roles
        print()
        print(breakdowns, end="")
    if args.json is not None:
        payload = {"methods": results, "seconds_per_frame": spf}
        write_text_atomic(args.json, json.dumps(json_ready(payload), indent=1, allow_nan=False))
    return 0
