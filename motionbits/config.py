"""Configuration of the MotionBits segmenter.

Defaults are the paper's numbers (Supplement A, "Implementation Details") where the paper
gives one; every other default is ours, chosen on generated scenes and stated as such.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields, replace
from numbers import Integral, Real

__all__ = ["BACKENDS", "MotionBitsConfig"]

#: Accepted values of ``MotionBitsConfig.backend``.
BACKENDS = ("numpy", "torch", "torch:cpu", "torch:cuda", "torch:cuda:N")
_BACKEND_RE = re.compile(r"numpy|torch(:cpu|:cuda(:\d+)?)?")

# annotation -> (what the error message calls it, test); bool is no int here, an int is a float
_FIELD_TYPES = {
    "bool": ("True or False", lambda v: isinstance(v, bool)),
    "int": ("an integer", lambda v: isinstance(v, Integral) and not isinstance(v, bool)),
    "float": ("a number", lambda v: isinstance(v, Real) and not isinstance(v, bool)),
    "str": ("a string", lambda v: isinstance(v, str)),
}

#: Allowed values of the numeric fields, as intervals ("inf" = no upper bound).
_RANGES = {
    "n_nodes": "[16, 1000000]",
    "k_neighbors": "[1, 24]",
    "max_side": "[32, 16384]",
    "seed_fraction": "(0, 1]",
    "propagation_iters": "[1, inf)",
    "reseed_every": "[1, inf)",
    "mcl_expansion": "[2, inf)",
    "mcl_inflation": "(1, inf)",
    "mcl_max_iters": "[1, inf)",
    "mcl_stable_iters": "[1, inf)",
    "mcl_prune": "[0, inf)",
    "mcl_max_items": "[16, inf)",
    "ransac_threshold": "(0, inf)",
    "fb_sigma": "(0, inf)",
    "flow_noise": "(0, inf)",
    "move_threshold": "(0, inf)",
    "motion_evidence": "[0, inf)",
    "carry_tolerance": "(0, inf)",
    "carry_gradient": "[0, inf)",
    "cut_share": "[0, 1]",
    "camera_support": "(0, 1]",
    "camera_threshold": "(0, inf)",
    "camera_min_shift": "[0, inf)",
    "camera_parallax": "(0, 1]",
    "camera_tolerance": "[0, inf)",
    "min_cluster_nodes": "[1, inf)",
    "prior_bonus": "[0, inf)",
    "photo_weight": "[0, inf)",
    "flow_texture": "(0, inf)",
    "pixel_evidence": "[0, inf)",
    "edge_band": "[0, inf)",
    "colour_band": "[0, inf)",
    "relight_sigma": "[0, inf)",
    "reveal_tolerance": "[0, inf)",
    "reveal_covered": "(0, inf)",
    "match_iou": "[0, 1]",
    "merge_agree": "[0, inf)",
    "merge_disagree": "[0, inf)",
    "retire_margin": "[0, inf)",
    "refine_min_iou": "[0, 1]",
    "refine_max_outside": "[0, 1]",
}


def _in_range(value: float, interval: str) -> bool:
    """Whether ``value`` lies in an interval written like ``"(0, 1]"`` or ``"[16, inf)"``."""
    lo, hi = (float(v) for v in interval[1:-1].split(","))
    if value != value:  # NaN is in no interval
        return False
    above = value > lo if interval[0] == "(" else value >= lo
    below = value < hi if interval[-1] == ")" else value <= hi
    return above and below


@dataclass(frozen=True)
class MotionBitsConfig:
    """Parameters of :class:`motionbits.MotionBitsSegmenter`.

    Lengths in pixels refer to the *working* resolution (longest side ``max_side``), so
    one config behaves the same on 240p and 4K input.
    """

    # --- graph construction (paper Sec. 5.1, Supp. A) ---
    n_nodes: int = 10_000  # Supp. A: sqrt(n) x sqrt(n) = 100 x 100 grid
    k_neighbors: int = 5  # Supp. A: k = 5 nearest grid neighbours
    # Supp. A: parameters derived for 480x640 / 640x480 video. Longest side of the working
    # resolution; smaller inputs are upsampled only up to 640, never beyond
    max_side: int = 640

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
    # clustered through at most this many representatives (groups of neighbouring nodes).
    # 200 (was 400): clustering ~3x faster on the demo's ~300-node blocks, same labels on
    # the demo, sim40 robot/hand mIoU within 1 point (docs/speed.md, "Earlier sessions")
    mcl_max_items: int = 200
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
    # ours: a frame whose flow from the last frame explains (as above, both ways
    # consistent) less than this share of its pixels shows another scene -- a cut in an
    # edited video: the segmenter starts a new shot there (its motion state is reset, ids
    # go on; 0 = off). Measured: 0.0002 at a cut, >= 0.44 on every real and generated clip
    # we have (02_cups.mp4 at every 4th frame being the lowest)
    cut_share: float = 0.1
    # ours: camera motion compensation (motionbits/camera.py). A homography
    # fitted to the node flow by RANSAC is taken as the camera's motion when at least
    # this fraction of the reliable nodes are its inliers (1.0 = off) ...
    camera_support: float = 0.5
    camera_threshold: float = 1.0  # px: ... with this RANSAC inlier threshold ...
    camera_min_shift: float = 0.25  # px: ... and only if it moves the nodes more (median)
    # ours (motionbits/parallax.py): what the homography leaves is the static world's
    # parallax where one epipole explains the residual (above camera_threshold) of at least
    # this fraction of the reliable nodes; it is removed too (1.0 = homography only)
    camera_parallax: float = 0.1
    # ours: the motion the homography leaves is measured by a second flow, from the frame
    # to the previous frame warped by the homography (small displacements, which DIS
    # measures better than the camera's); False = the first flow composed with H (exact
    # flows, e.g. the oracle baseline, need no second pass)
    camera_reflow: bool = True
    # ours: the static world's model under a moving camera is good to about this many px:
    # a new MotionBit must beat "nothing moved" with that much misalignment forgiven (grey
    # change minus camera_tolerance x the local gradient; evidence.forgive_misalignment)
    camera_tolerance: float = 0.5

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
    # ours (evidence.static_residual), off by default: "nothing moved" also explains a pixel
    # whose change a smooth brightness gain explains -- a moving soft shadow, flicker,
    # exposure -- with the gain's smoothness this many grid cells (Gaussian sigma, e.g. 3);
    # it also explains flat bodies away (pickplace mIoU -7.5 with exact flow:
    # docs/reading_the_paper.md, "A change of light need not be motion")
    relight_sigma: float = 0.0
    # ours (motionbits/revealed.py): with a still camera, a pixel that looks as it did when
    # last seen standing still -- within reveal_tolerance grey levels (5x5 mean; 0 = off)
    # -- after something covered it (it differed by more than reveal_covered) is the static
    # world uncovered again: "nothing moved" explains it, whatever flow smeared into it;
    # reveal_covered is also how far a pixel must differ from the static world seen there
    # before to look otherwise (arrivals.py; completion.FirstLook, the scene first seen),
    # and reveal_tolerance how close a cast shadow keeps the texture it dims (the shadow
    # tests of revealed.py and completion.FirstLook.relit)
    reveal_tolerance: float = 10.0
    reveal_covered: float = 20.0
    # ours (masks.snap_to_edges): each shown mask is trimmed back to the strongest image
    # edge within this many grid cells of its outline (0 = off; the state is not trimmed)
    edge_band: float = 1.0
    # ours (colours.snap_to_colours): within this many grid cells of its outline, a shown
    # mask takes the pixels coloured like its inside and gives back those coloured like
    # the background around it (0 = off; the state keeps the motion's masks)
    colour_band: float = 1.25
    match_iou: float = 0.2  # a cluster inherits an id above this IoU with its old mask
    # ours (motionbits/merging.py): touching MotionBits are one body when one affine motion
    # explains the images of both within merge_agree grey levels of their own motions (at
    # some frame), and different bodies for good once it is worse by merge_disagree at two
    # frames (or by twice that at one; merging.DISAGREE_FRAMES, merging.AT_ONCE)
    merge_agree: float = 1.5
    merge_disagree: float = 6.0
    # ours (motionbits/retirement.py): a MotionBit is retired when the static world explains
    # its pixels better, by this many grey levels, than its own motion since its birth
    retire_margin: float = 5.0

    # --- optional learned refinement (paper Sec. 5.3: SAM2 prompted per MotionBit) ---
    # "none" (default) or "sam2": each frame's masks are refined by SAM2 from `sam2_path`
    # (motionbits/refine_sam2.py; needs torch + transformers, imported only then)
    refine: str = "none"
    sam2_path: str = ""  # SAM2 checkpoint folder (transformers format) or a reachable hub id
    refine_min_iou: float = 0.5  # ours: a refined mask must overlap its motion mask this much
    # ours: ... and have at most this fraction on static background away from the motion mask
    refine_max_outside: float = 0.1

    # --- temporal window (ours; the paper's constraints span the whole video) ---
    # ours: None = the temporal constraints (label history, past edge maxima) cover every
    # earlier frame, as in the paper; N >= 2 = only about the last N frames (more than
    # 3N/4 and at most N; motionbits/temporal.py), so that long videos do not keep old
    # splits forever
    window: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.backend, str) or not _BACKEND_RE.fullmatch(self.backend):
            raise ValueError(f"invalid MotionBitsConfig backend {self.backend!r}; choose one of "
                             + ", ".join(repr(b) for b in BACKENDS) + " (N = GPU index)")
        # Generic over the fields, so a new field is checked without touching this method:
        # its type comes from its annotation, its range (if any) from ``_RANGES``.
        for f in fields(self):
            value = getattr(self, f.name)
            kind = _FIELD_TYPES.get(f.type if isinstance(f.type, str) else f.type.__name__)
            if kind is not None and not kind[1](value):
                raise TypeError(f"MotionBitsConfig.{f.name} must be {kind[0]}, got "
                                f"{type(value).__name__} {value!r}")
            if f.name in _RANGES and not _in_range(value, _RANGES[f.name]):
                raise ValueError(f"invalid MotionBitsConfig value {f.name}={value!r}: must be in "
                                 f"{_RANGES[f.name]}")
        if self.merge_disagree < self.merge_agree:
            raise ValueError(f"MotionBitsConfig.merge_disagree ({self.merge_disagree!r}) must be "
                             f">= merge_agree ({self.merge_agree!r})")
        if self.window is not None and (isinstance(self.window, bool)
                                        or not isinstance(self.window, int) or self.window < 2):
            raise ValueError(f"invalid MotionBitsConfig value window={self.window!r}: must be "
                             "None (the whole video) or an int >= 2")
        if self.refine not in ("none", "sam2"):
            raise ValueError(f"invalid MotionBitsConfig refine {self.refine!r}; choose 'none' or 'sam2'")
        if self.refine == "sam2" and not self.sam2_path:
            raise ValueError("MotionBitsConfig(refine='sam2') needs sam2_path: a SAM2 checkpoint folder")

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
