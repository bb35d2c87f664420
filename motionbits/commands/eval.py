"""``motionbits eval``: score predicted label maps against a MoRiBo-format ground truth."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from motionbits.outputs import check_output_file, write_text_atomic

__all__ = ["register", "run", "parse_pred_spec"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "eval",
        help="score final-frame predictions on MoRiBo-format data (paper Table 2 layout)",
        description=(
            "Overlap P/R/F1/mIoU and Boundary P/R/F1 with Hungarian matching, macro-averaged "
            "over GT instances (paper section 6.1), per track and averaged over tracks. "
            "--pred holds per scene <scene>.png or a 'motionbits segment' output folder "
            "<scene>/ (its last labels/NNNNN.png is used)."
        ),
    )
    p.add_argument("--pred", required=True, action="append", metavar="[NAME=]DIR",
                   help="prediction folder; repeat for several methods (row name = NAME or "
                        "the folder name)")
    p.add_argument("--gt", required=True, metavar="DIR",
                   help="MoRiBo scene, track (folder of scenes) or folder of tracks")
    p.add_argument("--json", metavar="FILE", help="write all scores (fractions in [0,1]) here")
    p.add_argument("--pooled", action="store_true",
                   help="also print the pooled per-image (UOIS/OCID) table with %%75")
    p.add_argument("--missing", choices=("error", "empty"), default="error",
                   help="a scene without prediction: fail (default) or score it as empty")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def parse_pred_spec(spec: str) -> tuple[str, Path]:
    """``"name=dir"`` -> (name, dir); ``"dir"`` -> (folder name, dir).

    Raises:
        ValueError: an empty spec, NAME or DIR (``Path("")`` is the current folder).
    """
    if not spec.strip():
        raise ValueError("--pred is empty; name the prediction folder")
    if "=" in spec and not Path(spec).exists():
        name, _, folder = spec.partition("=")
        if not name.strip() or not folder.strip():
            raise ValueError(f"--pred {spec!r}: {'NAME' if not name.strip() else 'DIR'} of "
                             "NAME=DIR is empty")
        return name, Path(folder)
    path = Path(spec)
    return path.resolve().name, path


def run(args: argparse.Namespace) -> int:
    from motionbits.eval.dataset import evaluate_dataset
    from motionbits.eval.kinds import format_breakdowns
    from motionbits.eval.losses import format_losses
    from motionbits.eval.table import format_table, json_ready

    if args.json is not None:
        check_output_file(args.json, "--json")
    if not args.gt.strip():  # else the current folder
        raise ValueError("--gt is empty; name the ground-truth folder")
    preds = {}  # every --pred checked before any is scored
    for spec in args.pred:
        name, folder = parse_pred_spec(spec)
        if not folder.is_dir():
            raise FileNotFoundError(f"prediction folder not found: {folder}")
        if name in preds:
            raise ValueError(f"two --pred share the name {name!r}; use NAME=DIR")
        preds[name] = folder
    results = {name: evaluate_dataset(args.gt, folder, missing=args.missing,
                                      progress=not args.quiet)
               for name, folder in preds.items()}
    print(format_table(results, block="macro"), end="")
    if args.pooled:
        print()
        print(format_table(results, block="pooled"), end="")
    losses = format_losses(results)
    if losses:  # every scored body, by how its mark fails
        print()
        print(losses, end="")
    breakdowns = format_breakdowns(results)
    if breakdowns:  # scenes of motionbits synth name their bodies' kinds and roles
        print()
        print(breakdowns, end="")
    if args.json is not None:
        payload = next(iter(results.values())) if len(results) == 1 else {"methods": results}
        write_text_atomic(args.json, json.dumps(json_ready(payload), indent=1, allow_nan=False))
    return 0
