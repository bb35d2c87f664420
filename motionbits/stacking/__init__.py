"""Tower stacking from segmentation masks in MuJoCo: the paper's Table 3 (Supplement B).

Needs the ``[sim]`` extra for anything that simulates (MuJoCo is imported on first use).
See docs/stacking.md.
"""

from motionbits.stacking.perception import (
    HeightMap,
    PinholeCamera,
    WorldGrasp,
    finger_clearance,
    world_grasp,
)
from motionbits.stacking.run import GT, format_table, run_stacking, summarise
from motionbits.stacking.scene import CAMERA, CameraSpec, StackScene, build_scene
from motionbits.stacking.trial import (
    FAILURES,
    PushedScene,
    TrialConfig,
    TrialResult,
    push_scene,
    run_trial,
)

__all__ = [
    "CAMERA",
    "FAILURES",
    "GT",
    "CameraSpec",
    "HeightMap",
    "PinholeCamera",
    "PushedScene",
    "StackScene",
    "TrialConfig",
    "TrialResult",
    "WorldGrasp",
    "build_scene",
    "finger_clearance",
    "format_table",
    "push_scene",
    "run_stacking",
    "run_trial",
    "summarise",
    "world_grasp",
]
