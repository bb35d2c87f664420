"""Configuration of the MotionBits segmenter.

Defaults are the paper's numbers (Supplement A, "Implementation Details") where the paper
gives one; every other default is ours, chosen on generated scenes and stated as such.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

__all__ = ["BACKENDS", "MotionBitsConfig"]

#: Accepted values of ``MotionBitsConfig.backend``.
BACKENDS = ("numpy", "torch", "torch:cpu", "torch:cuda", "torch:cuda:N")
_BACKEND_RE = re.compile(r"numpy|torch(:cpu|:cuda(:\d+)?)?")


@dataclass(frozen=True)
class MotionBitsConfig:
    """Parameters of :class:`motionbits.MotionBitsSegmenter`.

    Lengths in pixels refer to the *working* resolution (longest side ``max_side``), so
    one config behaves the same on 240p and 4K input.
    """

    # --- graph construction (paper Sec. 5.1, Supp. A) ---
    n_nodes: int = 10_000  # Supp. A: sqrt(n) x sqrt(n) = 100 x 100 grid
    k_neighbors: int = 5  # Supp. A: k = 5 nearest grid neighbours
    max_side: int = 640  # Supp. A: parameters derived for 480x640 / 640x480 video

    # --- soft label propagation (paper Sec. 5.2, Supp. A) ---
    seed_fraction: float = 0.04  # Supp. A: C = 0.04 n seeds (C = 400 at n = 10,000)
    propagation_iters: int = 100  # Supp. A: R = 100 iterations
    reseed_every: int = 5  # Supp. A: r* = 5, "pour more paint" every 5 iterations

    # --- hard Markov clustering (paper Sec. 5.2, Supp. A) ---
    mcl_expansion: int = 2  # Supp. A: expansion 2
    mcl_inflation: float = 1.15  # Supp. A: inflation 1.15
    mcl_max_iters: int = 100  # ours: cap; MCL at 1.15 converges in 60-90 iterations
    # ours (fast path): stop once the node labels are unchanged this long; they settle in
    # 2-3 iterations while the iterate takes 45-60 more to become idempotent
    mcl_stable_iters: int = 2
    mcl_prune: float = 0.6  # ours: prune entries < mcl_prune / m (m = nodes clustered)
    # ours (fast path): dense MCL costs m^3 on a block of m nodes; a larger block is
    # clustered through at most this many representatives (groups of neighbouring nodes)
    mcl_max_items: int = 400
    # ours: True is the reference computation (float64, MCL iterated until idempotent);
    # False (default) is the fast path: float32, MCL stops once its labels are stable
    exact: bool = False
    # ours: where propagation, MCL and the local twist fits run. "numpy" (default, CPU);
    # "torch" = torch on CUDA if available, else on the CPU; "torch:cpu", "torch:cuda",
    # "torch:cuda:N" pin the device. Same labels as "numpy" up to floating-point rounding;
    # needs torch (pip install torch), imported only when a segmenter is built with it.
    backend: str = "numpy"

    # --- flow and local twists (ours; the paper uses MemFlow and does not give these) ---
    flow: str = "dis-medium"  # default flow backend: OpenCV DIS, MEDIUM preset
    ransac_threshold: float = 0.5  # px: inlier residual of a node's 2-point RANSAC
    fb_sigma: float = 1.0  # px: forward-backward error scale of the Kabsch weights
    flow_noise: float = 0.15  # px: flow noise floor that regularises each covariance
    move_threshold: float = 0.6  # px/frame: a node "moves" above this displacement
    # ours: a new MotionBit is born only if its flow explains its nodes' neighbourhoods
    # better than "static" by this many grey levels on average (0 = off): textureless
    # regions get flow smeared in from moving edges, which is no evidence of motion
    motion_evidence: float = 1.0
    # ours: a label carried from the last frame holds a pixel only where the flow's
    # correspondence explains its appearance: mean |I_t - I_t-1 pulled back| (5x5) below
    # carry_tolerance grey levels + carry_gradient x the local gradient (px of flow error
    # tolerated on texture). Uncovered background fails it and does not inherit a label.
    carry_tolerance: float = 12.0
    carry_gradient: float = 1.0
    # ours: camera motion compensation (motionbits/camera.py). A similarity transform
    # fitted to the node flow by RANSAC is taken as the camera's motion when at least
    # this fraction of the reliable nodes are its inliers (1.0 = off) ...
    camera_support: float = 0.5
    camera_threshold: float = 1.0  # px: ... with this RANSAC inlier threshold ...
    camera_min_shift: float = 0.25  # px: ... and only if it moves the nodes more (median)

    # --- pixel masks and identities (ours) ---
    min_cluster_nodes: int = 4  # clusters with fewer nodes are noise
    prior_bonus: float = 0.35  # px: residual credit for keeping last frame's label
    photo_weight: float = 0.1  # px of mask cost per grey level of photometric residual
    # ours: a pixel's flow residual counts fully where its image gradient reaches this many
    # grey levels per px, proportionally less on flatter pixels (their flow is interpolated)
    flow_texture: float = 4.0
    # ours: a pixel's carried MotionBit label is credited (prior_bonus) only where the
    # MotionBit's motion once explained that pixel better than "static" by this many grey
    # levels (3x3 mean) -- a label smeared onto a flat static region does not persist
    pixel_evidence: float = 3.0
    match_iou: float = 0.2  # a cluster inherits an id above this IoU with its old mask
    # ours (motionbits/merging.py): touching MotionBits are one body when one affine motion
    # explains the images of both within merge_agree grey levels of their own motions (at
    # some frame), and different bodies for good once it is worse by merge_disagree
    merge_agree: float = 1.5
    merge_disagree: float = 6.0
    # ours (motionbits/retirement.py): a MotionBit is retired when the static world explains
    # its pixels better, by this many grey levels, than its own motion since its birth
    retire_margin: float = 5.0

    def __post_init__(self) -> None:
        if not isinstance(self.backend, str) or not _BACKEND_RE.fullmatch(self.backend):
            raise ValueError(f"invalid MotionBitsConfig backend {self.backend!r}; choose one of "
                             + ", ".join(repr(b) for b in BACKENDS) + " (N = GPU index)")
        checks = {
            "n_nodes": self.n_nodes >= 16,
            "k_neighbors": 1 <= self.k_neighbors <= 24,
            "max_side": self.max_side >= 32,
            "seed_fraction": 0.0 < self.seed_fraction <= 1.0,
            "propagation_iters": self.propagation_iters >= 1,
            "reseed_every": self.reseed_every >= 1,
            "mcl_expansion": self.mcl_expansion >= 2,
            "mcl_inflation": self.mcl_inflation > 1.0,
            "mcl_max_iters": self.mcl_max_iters >= 1,
            "mcl_stable_iters": self.mcl_stable_iters >= 1,
            "mcl_prune": self.mcl_prune >= 0.0,
            "mcl_max_items": self.mcl_max_items >= 16,
            "ransac_threshold": self.ransac_threshold > 0,
            "fb_sigma": self.fb_sigma > 0,
            "flow_noise": self.flow_noise > 0,
            "move_threshold": self.move_threshold > 0,
            "motion_evidence": self.motion_evidence >= 0,
            "carry_tolerance": self.carry_tolerance > 0,
            "carry_gradient": self.carry_gradient >= 0,
            "camera_support": 0.0 < self.camera_support <= 1.0,
            "camera_threshold": self.camera_threshold > 0,
            "camera_min_shift": self.camera_min_shift >= 0,
            "min_cluster_nodes": self.min_cluster_nodes >= 1,
            "prior_bonus": self.prior_bonus >= 0,
            "photo_weight": self.photo_weight >= 0,
            "flow_texture": self.flow_texture > 0,
            "pixel_evidence": self.pixel_evidence >= 0,
            "match_iou": 0.0 <= self.match_iou <= 1.0,
            "merge_agree": self.merge_agree >= 0,
            "merge_disagree": self.merge_disagree >= self.merge_agree,
            "retire_margin": self.retire_margin >= 0,
        }
        bad = [name for name, ok in checks.items() if not ok]
        if bad:
            values = ", ".join(f"{name}={getattr(self, name)!r}" for name in bad)
            raise ValueError(f"invalid MotionBitsConfig value(s): {values}")

    @property
    def grid_side(self) -> int:
        """Nodes per side of the square node grid: round(sqrt(n))."""
        return max(4, int(round(math.sqrt(self.n_nodes))))

    @property
    def seed_stride(self) -> int:
        """Grid stride between seeds so that about ``seed_fraction * n`` seeds are laid."""
        return max(1, int(round(1.0 / math.sqrt(self.seed_fraction))))

    def with_(self, **changes) -> "MotionBitsConfig":
        """A copy with some fields changed (the config itself is frozen)."""
        return replace(self, **changes)
