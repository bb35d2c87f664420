"""The online MotionBits segmenter (paper Algorithm 1): the steps of a frame, in order.

Each step lives in its own module; this one holds the stream's state and calls them.
"""

from __future__ import annotations

import time
from concurrent.futures import Future
from contextlib import contextmanager
from functools import cache
from typing import Iterator

import cv2
import numpy as np
from threadpoolctl import ThreadpoolController

from motionbits.apart import GAP_CELLS, split_apart
from motionbits.aperture import (carried_joins, flat_link_candidates, half_colour_gradient,
                                 join_flat_links)
from motionbits.arrivals import Arrivals
from motionbits.backend import make_ops
from motionbits.boxes import label_areas, nonzero_box, run_counts
from motionbits.camera import compensate_camera
from motionbits.colours import snap_to_colours
from motionbits.completion import CutMemory, FirstLook, complete_masks, complete_small_marks
from motionbits.config import MotionBitsConfig
from motionbits.evidence import (
    appearance_consistent, forgive_misalignment, gradient_magnitude, motion_gain, pull_back,
    static_residual)
from motionbits.flow import (FlowBackend, check_flow, forward_backward_error, make_flow,
                             sample_maps)
from motionbits.graph import (
    apply_temporal_constraints,
    local_covariances,
    project_past_max,
    symmetric_graph,
    twist_noise_covariance,
    twist_edge_weights,
)
from motionbits.identity import identify_clusters
from motionbits.masks import (SPECK_CELLS, StaticCost, assign_pixels, drop_labels,
                              fit_cluster_motions, flat_looks, hide_edgeless, hide_small,
                              hide_thin, remove_specks, snap_to_edges, static_cost,
                              trim_flat_background)
from motionbits.merging import (MIN_MOVED, MotionBitGroups, apply_joins, drop_seen_still,
                                join_convex, mostly_moving, observe_touching, seen_still,
                                standing_still)
from motionbits.mcl import cluster_components
from motionbits.nodes import NodeGrid, binary_fill_holes, sample_bilinear
from motionbits.numbering import ShownNumbers, by_number
from motionbits.parallax import ParallaxOnly, moves_along_lines
from motionbits.propagation import grid_seeds, propagate_components
from motionbits.records import (
    MotionBit, MotionBitsResult, MotionSpans, build_result, group_map, moving_ids, twist_sources)
from motionbits.resting import RestingMarks, looks_tested
from motionbits.retirement import (APART_CELLS, CarriedBodies, Origin, moved_marks, moved_once,
                                   retire, retire_shadows)
from motionbits.revealed import StaticMemory, carry_at_rest, grey_change
from motionbits.second_thread import Task, second_thread
from motionbits.setdown import SetDown
from motionbits.shadows import cast_shadows, shadow_map, trim_shadows
from motionbits.temporal import TemporalState
from motionbits.twists import fit_local_motions, nodes_to_fit, refine_moving_motions
from motionbits.video import FrameSource, as_rgb_frame, iter_frames

__all__ = ["MotionBit", "MotionBitsResult", "MotionBitsSegmenter", "segment_video", "STAGES"]

#: Shortest side, in working pixels, that the default flow (OpenCV DIS) handles.
MIN_WORK_SIDE = 20
#: Smaller inputs are upsampled to at most this longest side (the paper's 640x480, where
#: the pixel parameters hold); ``max_side`` never upsamples beyond max(input, this).
REFERENCE_SIDE = 640


def work_size(height: int, width: int, max_side: int) -> tuple[int, int]:
    """(H, W) at which the segmenter processes frames of ``height`` x ``width``: longest
    side ``max_side``, but above the input's size only up to ``REFERENCE_SIDE`` (pixel
    parameters are tuned there): the cost is bounded by design."""
    side = min(max_side, max(height, width, REFERENCE_SIDE))
    scale = side / max(height, width)
    return int(round(height * scale)), int(round(width * scale))


def min_short_side(long_side: int, max_side: int) -> int:
    """Shortest frame side the segmenter accepts when the longest is ``long_side``: both
    working sides (:func:`work_size`) need ``MIN_WORK_SIDE`` px for the optical flow."""
    scale = min(max_side, max(long_side, REFERENCE_SIDE)) / long_side
    short = max(1, int((MIN_WORK_SIDE - 1) / scale))  # rounds to at most MIN_WORK_SIDE - 1
    while min(work_size(short, long_side, max_side)) < MIN_WORK_SIDE:
        short += 1
    return short


#: a MotionBit (or merged group) is shown only if its shown mask -- trimmed to the image's
#: edges -- covers this many grid cells (about 250 px at 640x480, 0.08% of the frame; a
#: mark on less is hard to read). Round 16: 4 -> 8 cut the spurious MotionBits by a third
#: (most were 130-300 px: pieces of smeared flow, shadows, arrivals) and hid one body of
#: the 9 under 400 px in 230 generated scenes that had been found (round 16,
#: docs/reading_the_paper.md, "Births need visible motion, twice").
MIN_SHOWN_CELLS = 8

#: Stage names of the per-frame timing report, in pipeline order. "flow" is the flow
#: backend alone (both directions, validated); "carry" is the work on the two flows before
#: the twists: grey frames, the previous frame pulled back, image gradients, the labels and
#: their history carried, and where a carried label still holds -- and, on the second
#: thread meanwhile (:mod:`motionbits.second_thread`), the forward-backward error and the
#: camera's motion, waited for. "bookkeeping" makes the masks shown while the second
#: thread brings the memories up to date, refines the reported twists and folds the
#: label history.
STAGES = ("resize", "flow", "carry", "twists", "graph", "propagation", "clustering", "masks",
          "merging", "bookkeeping")

#: px: forward-backward errors are capped here (a pixel whose backward target leaves the
#: image has an infinite or NaN error: no reliable flow).
FB_ERROR_CAP = 1e3
#: Smallest side (px, odd) of the window of a new MotionBit's photometric evidence (else
#: one grid cell).
EVIDENCE_WINDOW = 3


def _gray(frame: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY).astype(np.float32)


class MotionBitsSegmenter:
    """Online, learning-free segmentation of moving rigid bodies.

    Feed frames one at a time with :meth:`update`; each call returns the MotionBits of that
    frame using only the frames seen so far. The first frame returns all-background labels.
    State is constant in size: the previous frame, the previous label map, one integer map
    of the label history and the largest past weight of each graph edge (with
    ``config.window``, a few staggered copies of the last two: see
    :mod:`motionbits.temporal`).

    Args:
        config: parameters; defaults are the paper's.
        flow: a flow backend ``flow(prev, next) -> (H, W, 2)``; default from ``config.flow``.

    With ``config.refine="sam2"`` every result's labels are refined by SAM2 after the
    frame is segmented (``self.refiner``, :mod:`motionbits.refine_sam2`); the segmenter's
    own state keeps the motion masks.

    Example:
        >>> from motionbits import MotionBitsSegmenter
        >>> from motionbits.synth import demo_clip
        >>> clip = demo_clip(n_frames=4, size=(120, 160))
        >>> seg = MotionBitsSegmenter()
        >>> for frame in clip.frames:
        ...     result = seg.update(frame)
        >>> result.labels.shape
        (120, 160)
    """

    def __init__(self, config: MotionBitsConfig | None = None, flow: FlowBackend | None = None):
        if config is not None and not isinstance(config, MotionBitsConfig):
            # else "'dict' object has no attribute 'flow'" (and {} quietly meant the defaults)
            hint = "; use MotionBitsConfig(**config)" if isinstance(config, dict) else ""
            raise TypeError(f"config must be a MotionBitsConfig or None, got "
                            f"{type(config).__name__}{hint}")
        self.config = config if config is not None else MotionBitsConfig()
        self.flow = make_flow(flow if flow is not None else self.config.flow)
        self._ops = make_ops(self.config.backend)  # twist fits, propagation, MCL
        self.refiner = None  # optional post-step on each frame's labels (config.refine)
        if self.config.refine == "sam2":  # imports torch + transformers only now
            from motionbits.refine_sam2 import Sam2Refiner

            self.refiner = Sam2Refiner.from_config(self.config)
        self._threads = ThreadpoolController()  # after make_ops, the refiner: sees torch's OpenMP too
        self._helper = second_thread()  # work beside the main thread's (second_thread.py)
        self.reset()

    def reset(self) -> None:
        """Forget the stream: the next frame is treated as the first."""
        self.frame_index = -1
        self._input_size: tuple[int, int] | None = None
        self._work_size: tuple[int, int] | None = None
        self._grid: NodeGrid | None = None
        self._seeds: np.ndarray | None = None
        self._noise_cov: np.ndarray | None = None  # (n, 3, 3) twist covariance of flow noise
        self._next_id = 1
        self._spans = MotionSpans()  # first / last frame each id moved
        self._timings: dict[str, float] = {}
        self._new_shot()

    def _new_shot(self) -> None:
        """Forget the motion state (at the start, or at a cut): the next frame is a shot's
        first. Ids go on from where they were."""
        self._prev: np.ndarray | None = None
        self._prev_gray: np.ndarray | None = None  # (h, w) float32 grey of ``_prev``
        self._origins: dict[int, Origin] = {}  # id -> its birth frame and motion since
        self._first: Origin | None = None  # the first frame and the world's motion since
        self._tentative: set[int] = set()  # ids born at the last frame, not yet confirmed
        # pieces a MotionBit left behind (a body set down), new MotionBits
        self._setdown = SetDown(self.config.pixel_evidence, self.config.carry_tolerance)
        self._groups = MotionBitGroups(self.config.merge_agree, self.config.merge_disagree)
        self._cuts = CutMemory()  # the marks at rest completed at the last frame
        self._rest_marks = RestingMarks()  # the marks shown at the last frame (resting.py)
        self._numbers = ShownNumbers()  # the numbers the marks are shown under (numbering.py)
        self._camera_moved = False  # the camera's motion was found at the last frame (parallax)
        self._resting: set[int] = set()  # ids at rest at the last frame
        self._parallax = ParallaxOnly()  # MotionBits moved only along epipolar lines
        if self._work_size is None:  # sized at the stream's first frame (_start)
            self._labels = self._earned = self._still = self._joined = None
            self._temporal = self._memory = self._arrivals = self._first_look = None
            return
        hw, ww = self._work_size
        self._labels = np.zeros((hw, ww), np.int32)  # working-resolution labels
        # label history and largest earlier edge weights (whole video or config.window)
        self._temporal = TemporalState((hw, ww), self._grid.neighbors.shape, self.config.window)
        self._earned = np.zeros((hw, ww), np.int32)  # 1 = its MotionBit showed there (masks)
        self._still = np.zeros((hw, ww), np.int32)  # 1 + last frame seen standing still (merging)
        self._joined = np.zeros((hw, ww), np.int32)  # id of the mask that joined it (aperture.py)
        self._memory = StaticMemory((hw, ww), self.config.reveal_tolerance,  # revealed.py
                                    self.config.reveal_covered)
        self._arrivals = Arrivals((hw, ww), self.config.reveal_covered,  # arrivals.py
                                  self.config.carry_tolerance, self.config.reveal_tolerance)
        self._first_look = FirstLook((hw, ww), self.config.reveal_covered,  # completion.py
                                     self.config.reveal_tolerance)

    # ------------------------------------------------------------------ helpers
    @contextmanager
    def _stage(self, name: str) -> Iterator[None]:
        t0 = time.perf_counter()
        yield
        self._timings[name] = self._timings.get(name, 0.0) + 1000 * (time.perf_counter() - t0)

    def _start(self, frame: np.ndarray) -> None:
        h, w = frame.shape[:2]
        hw, ww = self._work_size = work_size(h, w, self.config.max_side)
        if min(hw, ww) < MIN_WORK_SIDE:
            raise ValueError(
                f"frame {self.frame_index + 1} is {w}x{h}: at max_side={self.config.max_side} it is "
                f"processed at {ww}x{hw}, but both sides need at least {MIN_WORK_SIDE} px for "
                "the optical flow; crop it or raise max_side")
        self._input_size = (h, w)
        self._grid = NodeGrid.build(hw, ww, self.config.grid_side, self.config.k_neighbors)
        self._seeds = grid_seeds(self._grid.rows, self._grid.cols, self.config.seed_stride)
        self._noise_cov = twist_noise_covariance(self._grid.points, self._grid.neighbors,
                                                 self.config.flow_noise)
        self._new_shot()

    def _to_work(self, frame: np.ndarray) -> np.ndarray:
        hw, ww = self._work_size
        if frame.shape[:2] == (hw, ww):
            return frame
        interp = cv2.INTER_AREA if hw < frame.shape[0] else cv2.INTER_LINEAR
        return cv2.resize(frame, (ww, hw), interpolation=interp)

    def _empty_result(self) -> MotionBitsResult:
        h, w = self._input_size
        g = self._grid
        return MotionBitsResult(self.frame_index, np.zeros((h, w), np.int32), [],
                                np.zeros((g.rows, g.cols), np.int32), dict(self._timings))

    @property
    def backend(self) -> str:
        """Where the heavy steps run: ``"numpy"`` or ``"torch:<device>"`` (resolved)."""
        return self._ops.name

    def __call__(self, frames: FrameSource) -> list[np.ndarray]:
        """Segment one whole video from its first frame: one (H, W) int32 label map per
        frame (the ``frames -> label maps`` interface of ``somprompt.GroundedVQA``).

        Resets the stream first, so each call is a new video. ``frames``: anything
        :func:`motionbits.video.iter_frames` reads (file, folder, array, frames).
        """
        self.reset()
        return [self.update(frame).labels for frame in iter_frames(frames)]

    # ------------------------------------------------------------------ main step
    def update(self, frame: np.ndarray) -> MotionBitsResult:
        """Segment the next frame of the stream.

        Args:
            frame: (H, W, 3) uint8 RGB (grayscale (H, W) and RGBA are converted). Every frame
                of a stream must have the same size.

        Returns:
            :class:`MotionBitsResult` with labels at the input size.
        """
        # The matrix products here are small (at most a few hundred rows): BLAS / OpenMP
        # threads (numpy, scipy, torch on the CPU) only add hand-off and spin-waiting, which
        # multiplies their cost on a busy CPU. OpenCV's own thread pool is not affected.
        with self._threads.limit(limits=1):
            try:
                result = self._update(frame)
            except BaseException:
                # the second thread's work for this frame ends before the error reaches the
                # caller (its tasks run in order: an empty one waits for them), so that
                # nothing writes into the stream's state after, e.g., a reset()
                self._helper.submit(int).result()
                raise
            return result if self.refiner is None else self.refiner.apply(frame, result)

    def _update(self, frame: np.ndarray) -> MotionBitsResult:
        frame = as_rgb_frame(frame, name=f"frame {self.frame_index + 1}")
        self._timings = {}
        if self._input_size is not None and frame.shape[:2] != self._input_size:
            raise ValueError(
                f"frame {self.frame_index + 1} is {frame.shape[1]}x{frame.shape[0]} but the stream "
                f"started at {self._input_size[1]}x{self._input_size[0]}: the frames of one video "
                "must all have one size (call reset() before a new video)"
            )
        if self._input_size is None:
            self._start(frame)  # raises for a frame too small, before the stream counts it
        self.frame_index += 1
        with self._stage("resize"):
            cur = self._to_work(frame)
        if self._prev is None:
            self._prev, self._prev_gray = cur, _gray(cur)
            return self._empty_result()
        cfg, grid = self.config, self._grid
        with self._stage("flow"):
            flow_fwd = check_flow(self.flow(self._prev, cur), cur.shape[:2], self.flow)
            flow_back = check_flow(self.flow(cur, self._prev), cur.shape[:2], self.flow)

        with self._stage("carry"):
            back_maps = sample_maps(flow_back)  # where each pixel came from, (h, w) x and y
            # the flow's reliability and the static world's (the camera's) motion, on the
            # second thread while this one carries the last frame's state
            grid_motion = self._helper.submit(self._world_motion, flow_fwd, flow_back,
                                              back_maps, cur)
            # last frame's labels and label history, carried to this frame
            cur_g, prev_g = _gray(cur), self._prev_gray
            raw_prev_g = prev_g
            if self._first is None:
                self._first = Origin(raw_prev_g, np.eye(3), np.eye(3))
            pulled = pull_back(prev_g, flow_back, back_maps)
            gradient = gradient_magnitude(cur_g)
            (prior, earned, still_seen, joined), history = self._temporal.carry(
                [self._labels, self._earned, self._still, self._joined], flow_back, back_maps)
            earned = earned > 0
            # a carried label holds a pixel only where the flow is consistent both ways and
            # its correspondence explains the pixel's appearance: uncovered background
            # does not inherit the label of the body that uncovered it
            explained = appearance_consistent(cur_g, pulled, gradient,
                                              tolerance=cfg.carry_tolerance,
                                              gradient_gain=cfg.carry_gradient)
            # the flat regions' gradient for the masks shown, while the camera's motion comes
            half_gradient = half_colour_gradient(cur)
            fb_err, seen_pts, reliability, camera = grid_motion.result()
            reliable = fb_err < cfg.fb_sigma
            prior_valid = reliable & explained
            # another scene: a cut, a new shot
            if np.count_nonzero(prior_valid) / prior_valid.size < cfg.cut_share:
                self._new_shot()
                self._prev, self._prev_gray = cur, cur_g
                return self._empty_result()

        with self._stage("twists"):
            pts = grid.points
            ix = np.clip(np.round(pts).astype(np.int64), 0, [grid.width - 1, grid.height - 1])
            hist_nodes = history[ix[:, 1], ix[:, 0]]
            # motion is measured against the dominant (camera) motion (flow_m, prev_m);
            # label maps are still carried with the true flow (but those at rest)
            flow_m, prev_m, back_pts, cam, world, epipole = camera
            self._camera_moved = cam is not None
            if prev_m is not self._prev:  # the camera-stabilised frame ("nothing moved");
                prev_g = _gray(prev_m)  # pulling it back along flow_m gives ``pulled`` again
            # how far "nothing moved" misses each pixel, and the frame's flat regions (the
            # flat links', the overhangs'), on the second thread meanwhile
            looked = self._helper.submit(self._static_look, cur, cur_g, prev_g, world)
            flats = self._helper.submit(flat_looks, cur, half_gradient)
            if world is not None and self._resting:
                # the MotionBits at rest follow the static world's model, not the flow
                prior, prior_valid = carry_at_rest(
                    prior, prior_valid, self._labels, world, self._resting,
                    lambda: appearance_consistent(cur_g, prev_g, gradient,
                                                  tolerance=cfg.carry_tolerance,
                                                  gradient_gain=cfg.carry_gradient))
            # and what "nothing moved" costs at each pixel, for the masks
            costs = self._helper.submit(self._static_cost, looked, flow_m, gradient, prior,
                                        prior_valid, earned, reliable)
            prior_nodes = np.where(prior_valid[ix[:, 1], ix[:, 0]], prior[ix[:, 1], ix[:, 0]], 0)
            motions = fit_local_motions(
                pts, back_pts, grid.neighbors, reliability, cfg.ransac_threshold,
                dtype=self._dtype, nodes=None if cfg.exact else nodes_to_fit(
                    back_pts - pts, prior_nodes, (grid.rows, grid.cols), cfg.move_threshold),
                fit_fn=self._ops.fit_neighbourhoods)

        with self._stage("graph"):
            cov = local_covariances(motions.twist, grid.neighbors, self._noise_cov)
            raw = twist_edge_weights(motions.twist, grid.neighbors, cov)
            source = grid.nearest_node(seen_pts)
            past = self._temporal.project(lambda pm: project_past_max(pm, grid, source))
            weights = apply_temporal_constraints(raw, grid.neighbors, hist_nodes, past)
            # eq. 4: a node belongs to the moving set if it moves now or was part of a
            # MotionBit at the last frame; enclosed holes (e.g. near a centre of rotation,
            # where points barely move but share the body's twist) are filled.
            active = (motions.displacement > cfg.move_threshold) | (prior_nodes != 0)
            active = binary_fill_holes(active.reshape(grid.rows, grid.cols)).ravel()
            w = symmetric_graph(weights, grid.neighbors, keep=active)
            active_idx = np.flatnonzero(active)

        with self._stage("propagation"):
            b, comp, n_seeds = propagate_components(
                w, np.flatnonzero(np.isin(active_idx, self._seeds)), cfg.propagation_iters,
                cfg.reseed_every, dtype=self._dtype, propagate_fn=self._ops.propagate_labels)

        with self._stage("clustering"):
            node_cluster = cluster_components(
                b, w, comp, n_seeds, active_idx, grid.n, grid.cols,
                max_items=None if cfg.exact else cfg.mcl_max_items,
                expansion=cfg.mcl_expansion, inflation=cfg.mcl_inflation, prune=cfg.mcl_prune,
                max_iters=cfg.mcl_max_iters,
                stable_iters=None if cfg.exact else cfg.mcl_stable_iters, dtype=self._dtype,
                block_fn=self._ops.mcl_block)

        with self._stage("masks"):
            # computed only if some cluster is a candidate for a new MotionBit
            win = max(EVIDENCE_WINDOW, int(round(max(grid.cell))) | 1)
            still, revealed, change = looked.result()
            # births only (computed once, if a cluster asks); under a moving camera a birth
            # must beat the static world's model given its error
            evidence = cache(lambda: motion_gain(
                still if cam is None else forgive_misalignment(still, gradient,
                                                               cfg.camera_tolerance),
                cur_g, pulled, win)[ix[:, 1], ix[:, 0]])
            # where something other than the static world last seen there stands now (a
            # newborn tumbling block, a body set down): evidence that no 2D motion gives
            changed = self._memory.changed()
            novel = None if changed is None else cache(lambda: changed[ix[:, 1], ix[:, 0]])
            first_new, unconfirmed = self._next_id, self._tentative
            node_ids, ids, self._tentative, self._next_id = identify_clusters(
                node_cluster, motions.displacement, prior[ix[:, 1], ix[:, 0]], evidence,
                (grid.rows, grid.cols), self._next_id, self._tentative,
                min_nodes=cfg.min_cluster_nodes, match_iou=cfg.match_iou,
                move_threshold=cfg.move_threshold, motion_evidence=cfg.motion_evidence,
                novel=novel)
            thetas, trans = fit_cluster_motions(pts, back_pts, reliability, node_ids, ids,
                                                cfg.ransac_threshold)
            # ids carried validly (np.unique's result, without its sort)
            carried = nonzero_box(prior)
            carried_ids = prior[carried]
            kept = np.setdiff1d(np.flatnonzero(run_counts(
                carried_ids[prior_valid[carried] & (carried_ids > 0)])), ids)
            moving = moving_ids(pts, node_ids, ids, thetas, trans, cfg.move_threshold)
            # born last frame and not moving now: gone, unless that frame's motion was a
            # body's (a block knocked across the table stops within a frame or two)
            stopped = kept[np.isin(kept, list(unconfirmed))]
            if len(stopped):
                busy = grid.to_image(np.isin(node_ids, list(moving)).view(np.uint8)) > 0
                kept = np.setdiff1d(kept, np.setdiff1d(stopped, list(moved_once(
                    self._origins, stopped, prior, prior_valid, busy, cam, cur_g,
                    int(round(APART_CELLS * max(grid.cell))), cfg.retire_margin,
                    cfg.carry_tolerance))))
            carried_earned = earned
            speed, standing, static = costs.result()
            labels, earned = assign_pixels(
                grid, node_ids, ids, thetas, trans, flow_m, cur_g, prev_g, static, prior,
                prior_valid, earned, bonus=cfg.prior_bonus, photo_weight=cfg.photo_weight,
                evidence=cfg.pixel_evidence, kept=kept, ambiguous=cfg.move_threshold)
            # a point seen standing still while a MotionBit moved does not join it now
            # (with a still camera: under a moving one, standing still is judged against
            # the static world's model, and parallax or a moving shadow's edge on a kerb
            # reads as motion the next frame)
            if cam is None:
                labels = drop_seen_still(labels, prior, still_seen, self._spans.first)
            cw, ch = grid.cell
            speck_area = int(np.ceil(SPECK_CELLS * cw * ch))
            labels = remove_specks(labels, min_area=speck_area)
            # a stopped body that something passed in front of: its pixels, seen again as
            # they looked when it stood still, take its id back
            labels, back = self._memory.restore(labels, revealed, list(moving))
            if back is not None:
                earned = earned | back
            # bodies set down: pieces left behind by a moving MotionBit become MotionBits
            labels = self._setdown.confirm(labels, cur_g, prev_g)
            labels, held, self._next_id = self._setdown.split(
                labels, prior, prior_valid, carried_earned, ids, thetas, trans, cur_g, prev_g,
                grid.cell, self._next_id, cam, changed, moving)
            earned = earned | held
            # bodies that arrived out of their motion's sight (carried hidden under a
            # gripper, knocked across in a frame): new at rest where the static world was
            # (under a moving camera the memory follows the static world's model first)
            if world is not None:
                self._arrivals.follow(world)
                self._first_look.follow(world)
                self._cuts.follow(world)
                self._rest_marks.follow(world)
            labels, held, born, self._next_id = self._arrivals.place(
                labels, self._arrivals.find(cur, change, labels, grid.cell, moving,
                                            self._first_look),
                moving, int(round(max(grid.cell))), self._next_id)
            earned = earned | held
            self._setdown.adopt(born, labels, grid.cell, moving)
            for i in self._setdown.pending:
                self._spans.inherit(i, self._setdown.parent[i], self.frame_index - 1)
            # (a body found where it came to rest moved by itself: never parallax only)
            self._parallax.arrived(self._setdown.pending)

        with self._stage("merging"):
            self._spans.record(moving, self.frame_index)
            if epipole is not None:
                self._parallax.observe(pts, back_pts - pts, node_ids, moving, epipole)
            # when each node never in a MotionBit was last seen standing still (+1; 0: never)
            still_before = np.where(hist_nodes == 0, still_seen[ix[:, 1], ix[:, 0]], 0)
            observe_touching(self._groups, grid, labels, node_ids, ids, thetas, trans, moving,
                             first_new, still_before, prior_nodes, back_pts, reliability,
                             cur_g, prev_g, disagree=cfg.merge_disagree,
                             first_moved=self._spans.first,
                             min_agreeing=0.0 if cam is None else MIN_MOVED)
            observed = labels
            before = np.flatnonzero(label_areas(labels)[1:]) + 1
            labels, self._origins = retire(labels, self._origins, ids, thetas, trans,
                                           first_new, cam, raw_prev_g, cur_g, cfg.retire_margin,
                                           explained=cfg.carry_tolerance,
                                           first=self._first)
            # (a MotionBit found to be a cast shadow keeps the body it carried with it)
            labels = retire_shadows(labels, cur, self._memory, moving, self._spans.first,
                                    self.frame_index, CarriedBodies(
                                        grid.cell, cur_g, prev_g, ids, thetas, trans,
                                        cfg.pixel_evidence))
            present = (before if labels is observed  # none retired
                       else np.flatnonzero(label_areas(labels)[1:]) + 1)
            self._memory.forget(np.setdiff1d(before, present))  # retired
            rep = self._groups.representatives(present)
            group_of = dict(rep)  # each present id's group, shown or not
            # a MotionBit born this frame is shown once it moves again, or as part of a
            # group that is already shown; a piece set down, once it still stands at the
            # next frame (a solid body found at rest where the static world was, at once)
            shown = {r for i, r in rep.items()
                     if i not in self._tentative and i not in self._setdown.held_back}
            # ... and never a MotionBit whose motion has only been the static world's
            # parallax (a tall static body under a moving camera)
            static = self._parallax.ids(present)
            rep = {i: r if r in shown and i not in static else 0 for i, r in rep.items()}

        with self._stage("bookkeeping"):
            self._labels = labels
            self._resting = set(present.tolist()) - moving
            self._earned = (earned & (labels > 0)).astype(np.int32)
            self._setdown.record(raw_prev_g, ids, thetas, trans, cam)
            self._prev, self._prev_gray = cur, cur_g
            # the stream's memories brought up to date on the second thread, while this one
            # makes the masks shown up to their completion (the first step that reads them)
            remembered = self._helper.submit(self._remember, cur, cur_g, change, labels,
                                             standing, reliable,
                                             None if epipole is None else (flow_m, epipole))
            # the twists reported: each moving MotionBit's motion refined on its own pixels
            # (flow reads rotations low) -- those a shown MotionBit reports; on the second
            # thread after the memories, unless a flat link's test asks for them first
            source = twist_sources(node_ids, ids, rep)
            refined = Task(self._helper, refine_moving_motions, cur_g, prev_g, labels, ids,
                           thetas, trans, moving & set(source.values()))
            # then what only the next frame reads: the label history, where pixels stood
            folded = self._helper.submit(self._fold, labels, raw, still_seen, standing)
            # the masks shown (one per group) take the flat links that move along
            # themselves and are trimmed to the image's edges; the state keeps the motion's
            # masks (trimming them would compound from frame to frame)
            links = flat_link_candidates(labels, ids, cur, speed, joined,
                                         move_threshold=cfg.move_threshold,
                                         min_area=speck_area, flat_look=flats.result()[0])
            with_links = labels if links is None else join_flat_links(
                labels, links, ids, *refined.result(), cur_g, prev_g, still)
            self._joined = (np.zeros(labels.shape, np.int32) if with_links is labels  # none
                            else carried_joins(with_links, labels, group_of))
            state = group_map(with_links, rep)
            shown = snap_to_edges(state, cur,
                                  int(round(cfg.edge_band * max(grid.cell))))
            # a mask is shown if its outline is an image edge (a mask left on a flat table
            # looks like the table around it) and, once its overhangs onto flat background
            # are trimmed and it is completed, it covers MIN_SHOWN_CELLS grid cells
            # (smaller ones are flow noise, or a sliver of smeared flow); its outline goes
            # where its colours end (flow is smooth across a moving body's outline)
            shown = trim_flat_background(hide_edgeless(shown, gradient), cur, flats.result()[1])
            pieces = snap_to_colours(shown, cur, int(round(cfg.colour_band * max(grid.cell))))
            min_shown = MIN_SHOWN_CELLS * grid.cell[0] * grid.cell[1]
            # and each mark seen whole takes the rest of its body by colour (a moving one
            # only where its outline stops inside its body) -- the small ones last, where
            # the others left room, and only those that then cover MIN_SHOWN_CELLS
            moving_marks = {rep[i] for i in moving if rep.get(i)}  # shown labels moving now
            shadows, calm = remembered.result()
            first_look = self._first_look if calm is not None else None
            shown = complete_masks(hide_small(pieces, min_shown), cur, moving_marks, gradient,
                                   self._cuts, first_look,
                                   shadow=shadow_map(shadows, cur.shape[:2]))
            shown = complete_small_marks(pieces, shown, cur, min_shown, moving_marks,
                                         gradient, first_look)
            # without the static world under a cast shadow (which moves with its body)
            shown = trim_shadows(shown, shadows)
            # stripes are not a body (the flow along a wood grain's lines)
            thin_side = int(np.ceil(max(grid.cell)))
            shown = hide_thin(shown, thin_side)
            # a mark at rest that the steps above hid (they turn on the state's frayed
            # outline), on a body and an image that did not change, is shown as it was --
            # where other marks left room, and no smaller than they may be; what is held
            # passes the tests on a mark's own look again (an outline on image edges, not
            # a stripe)
            still_marks = {r for r in rep.values() if r} - moving_marks
            held, given = self._rest_marks.hold(shown, cur, state, still_marks, min_shown)
            shown = looks_tested(held, given, gradient, thin_side) if given else held
            # nothing moved where a mark stands as first seen (a static body marked through
            # parallax or smeared flow) -- unless its body's own motion since its birth
            # explains it better than the static world (a block nudged less than its size
            # looks much as first seen) -- nor where a mark at rest shows the table a body
            # first seen there has left
            if calm is not None:
                moved = moved_marks(shown, with_links, self._origins, moving)
                shown = drop_labels(shown, self._first_look.as_first_seen(shown, cur, moved))
                shown = drop_labels(shown, self._first_look.uncovered(shown, cur, still_marks))
            # marks at rest side by side that make one convex body are one (its faces,
            # marked apart and set down: nothing moves to tell); a mark moves here when
            # most of it does
            shown, rep = apply_joins(shown, rep, join_convex(
                shown, cur, mostly_moving(with_links, rep, moving, moving_marks),
                self._groups))
            # one mark, one connected body: the pieces of a mark far apart are shown apart
            split, rep, fresh, self._next_id = split_apart(
                shown, with_links, rep, source, self._next_id,
                gap=int(round(GAP_CELLS * max(grid.cell))), min_area=min_shown)
            if split is not shown:
                shown = split
                source = {**twist_sources(node_ids, ids, rep), **fresh}
            # each mark under the number its body was shown under (the state keeps the
            # groups' representatives)
            numbers, self._next_id = self._numbers.assign(shown, with_links, rep,
                                                          self._next_id)
            member_numbers, numbered_source = by_number(rep, source, numbers)
            thetas, trans = refined.result()
            folded.result()  # the stream's state whole before the frame's result is out
            result = build_result(self.frame_index, group_map(shown, numbers), node_ids, ids,
                                  thetas, trans, moving, member_numbers, numbered_source,
                                  self._spans, grid, self._input_size)
        result.timings = dict(self._timings)
        return result

    def _remember(self, cur: np.ndarray, cur_g: np.ndarray, change: np.ndarray,
                  labels: np.ndarray, standing: np.ndarray, reliable: np.ndarray,
                  parallax: tuple[np.ndarray, np.ndarray] | None
                  ) -> tuple[tuple[tuple[slice, slice], np.ndarray] | None, np.ndarray | None]:
        """Bring the static world's memory up to this frame (and the arrivals' and the
        first look's), given where the frame stands still (``standing``, (h, w) bool).
        ``parallax``: the (h, w, 2) flow relative to the static world's model and the (3,)
        epipole of its parallax (None: none found): what moves along its epipolar line is
        not seen moving by the arrivals (a tall static body under a moving camera, read
        through its parallax, is no body that arrived). Returns the cast shadows the
        memory saw before it moved on (:func:`motionbits.shadows.cast_shadows`) and the
        pixels it took in (None: the memory is off). Writes only those memories."""
        # before the memory moves on
        shadows = cast_shadows(self._memory, cur, labels, self._first_look)
        calm = self._memory.update(cur, cur_g, change, standing, labels)
        if calm is not None:
            moved = reliable & ~standing
            if parallax is not None:
                moved &= ~moves_along_lines(*parallax)
            self._arrivals.update(cur, calm, labels, moved)
            self._first_look.update(cur, calm, labels)
        return shadows, calm

    def _fold(self, labels: np.ndarray, raw: np.ndarray, still_seen: np.ndarray,
              standing: np.ndarray) -> None:
        """Fold this frame's labels into the label history and note where each pixel was
        last seen standing still. Only the next frame reads them; writes only those."""
        self._temporal.fold(raw, labels, margin=int(np.ceil(max(self._grid.cell))))
        self._still = seen_still(still_seen, standing, self.frame_index)

    def _static_look(self, cur: np.ndarray, cur_g: np.ndarray, prev_g: np.ndarray,
                     world: np.ndarray | None
                     ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """How far "nothing moved" misses each pixel ((h, w) float32 grey levels) -- also
        when only the light changed on it, and lowered where the static world is seen again
        after a body uncovered it -- those revealed pixels ((h, w) bool; None: the memory
        is off) and the grey change itself (:func:`motionbits.revealed.grey_change`, read
        where the memories look for what stands still). Under a moving camera the memory
        follows the static world's model (``world``) first. Writes only the static world's
        memory."""
        cfg = self.config
        still = (static_residual(cur_g, prev_g, cfg.relight_sigma * max(self._grid.cell))
                 if cfg.relight_sigma else np.abs(cur_g - prev_g))
        return (still, self._memory.observe(cur, cur_g, still, world),
                grey_change(cur_g, prev_g))

    def _static_cost(self, looked: Future, flow: np.ndarray, gradient: np.ndarray,
                     prior: np.ndarray, prior_valid: np.ndarray, earned: np.ndarray,
                     reliable: np.ndarray) -> tuple[np.ndarray, np.ndarray, StaticCost]:
        """How far each pixel moves by the camera-compensated ``flow`` ((h, w) float32 px),
        where the frame stands still ((h, w) bool, :func:`motionbits.merging.standing_still`)
        and what "nothing moved" costs at each pixel (:func:`motionbits.masks.static_cost`),
        given :meth:`_static_look`'s answer (``looked``: done, as the second thread runs
        its tasks in order). Reads and writes none of the stream's state."""
        cfg = self.config
        still, revealed, _ = looked.result()
        speed = cv2.magnitude(flow[..., 0], flow[..., 1])
        return (speed, standing_still(speed, reliable, cfg.move_threshold),
                static_cost(speed, gradient, still, prior, prior_valid, earned,
                            flow_texture=cfg.flow_texture, bonus=cfg.prior_bonus,
                            photo_weight=cfg.photo_weight, revealed=revealed))

    def _world_motion(self, flow_fwd: np.ndarray, flow_back: np.ndarray,
                      back_maps: tuple[np.ndarray, np.ndarray], cur: np.ndarray):
        """The flow's forward-backward error ((h, w) float32, capped), where the grid's
        nodes came from ((n, 2)), their reliability ((n,)) and the camera's motion
        (:func:`motionbits.camera.compensate_camera`'s tuple). Reads the stream's state,
        writes none of it."""
        cfg, pts = self.config, self._grid.points
        # pixels whose backward target leaves the image come back inf or nan (remap
        # interpolates the inf border): treat both as "no reliable flow" (fmin: the cap)
        fb_err = np.fmin(forward_backward_error(flow_back, flow_fwd, back_maps),
                         np.float32(FB_ERROR_CAP))
        seen_pts = pts + sample_bilinear(flow_back, pts)  # where the nodes came from
        node_err = sample_bilinear(fb_err[..., None], pts)[:, 0]
        reliability = np.exp(-((node_err / cfg.fb_sigma) ** 2))
        camera = compensate_camera(
            pts, seen_pts, reliability, flow_back, self._prev, support=cfg.camera_support,
            threshold=cfg.camera_threshold, min_shift=cfg.camera_min_shift,
            parallax=cfg.camera_parallax, grid_shape=(self._grid.rows, self._grid.cols),
            reflow=self.flow if cfg.camera_reflow else None, cur=cur,
            view_moving=self._camera_moved)
        return fb_err, seen_pts, reliability, camera

    @property
    def _dtype(self) -> type:
        return np.float64 if self.config.exact else np.float32


def segment_video(source: FrameSource, config: MotionBitsConfig | None = None, *,
                  flow: FlowBackend | None = None, every: int = 1) -> Iterator[MotionBitsResult]:
    """Segment a whole video, yielding one :class:`MotionBitsResult` per processed frame.

    Args:
        source: a video file, a folder of images, a (T, H, W, 3) uint8 array or an iterable
            of frames (see :func:`motionbits.video.iter_frames`).
        config: segmenter parameters.
        flow: optional flow backend.
        every: process every ``every``-th frame (temporal subsampling); ``frame_index`` of
            each result counts processed frames.

    Raises:
        TypeError: ``every`` is not an int.
        ValueError: ``every`` < 1.
    """
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)):
        raise TypeError(f"every must be an int >= 1, got {type(every).__name__} {every!r}")
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    seg = MotionBitsSegmenter(config, flow=flow)
    for i, frame in enumerate(iter_frames(source)):
        if i % every == 0:
            yield seg.update(frame)
