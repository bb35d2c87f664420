"""The README picture of one tower-stacking trial (not a test).

    PYTHONPATH=. python scripts/render_stacking_example.py [--method motionbits] [--seed 0]
        [--trial 0] [--out docs/img/stacking_motionbits.png]

Left: the push clip's last frame with the method's masks, numbered in the controller's
greedy order (largest first; masks with nothing standing in them are left out). Middle: the
gripper carrying an object to the tower. Right: the end of the trial. The caption printed
is the trial's outcome.
"""

from __future__ import annotations

import argparse

import cv2
import numpy as np
from PIL import Image

from motionbits.baselines import make_method
from motionbits.stacking.perception import world_grasp
from motionbits.stacking.sim import StackSim
from motionbits.stacking.trial import TrialConfig, push_scene, run_trial
from somprompt import draw_marks

CROP = (slice(40, 360), slice(0, 520))  # rows, cols of the work area at 640x480


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--method", default="motionbits")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--trial", type=int, default=0)
    ap.add_argument("--out", default="docs/img/stacking_motionbits.png")
    args = ap.parse_args()

    cfg = TrialConfig()
    pushed = push_scene(args.seed, args.trial, cfg)
    labels = np.asarray(make_method(args.method)(pushed.frames))
    frames: list[np.ndarray] = []
    result = run_trial(args.method, lambda _: labels, pushed, cfg, video=frames.append)

    sim = StackSim(pushed.scene)
    sim.set_state(pushed.state)
    cam, points = sim.camera(), sim.camera().backproject(sim.depth())
    sim.close()
    left = np.array(draw_marks(pushed.frames[-1], labels, mode="mask+contour"))
    ids, counts = np.unique(labels[labels > 0], return_counts=True)
    k = 0
    for i in ids[np.argsort(-counts, kind="stable")]:
        mask = labels == i
        g = world_grasp(mask, points) if mask.sum() >= cfg.min_mask_px else None
        if g is None or g.top < cfg.min_object_height:
            continue
        u, v = cam.project(np.array([[g.xy[0], g.xy[1], g.top]]))[0]
        cv2.putText(left, str(k), (int(u) - 5, int(v) + 5), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 3)
        cv2.putText(left, str(k), (int(u) - 5, int(v) + 5), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 1)
        k += 1
    stacking = frames[len(pushed.frames):]
    middle = stacking[len(stacking) // 2] if stacking else pushed.frames[-1]
    right = stacking[-1] if stacking else pushed.frames[-1]
    panels = [p[CROP] for p in (left, middle, right)]
    Image.fromarray(np.concatenate(panels, axis=1)).save(args.out)
    state = "success" if result.success else f"failed ({result.failure})"
    print(f"{args.method}, seed {args.seed}, trial {args.trial}: {state}, {result.stacked} stacked, "
          f"{result.n_masks} masks -> {args.out}")
    for line in result.log:
        print("  ", line)


if __name__ == "__main__":
    main()
