"""The online MotionBits segmenter (paper Algorithm 1)."""

from __future__ import annotations

import time
from contextlib import contextmanager
from functools import cache
from dataclasses import dataclass, field, replace
from typing import Iterator

import cv2
import numpy as np
from scipy import ndimage
from scipy.sparse.csgraph import connected_components
from threadpoolctl import ThreadpoolController

from motionbits.backend import make_ops
from motionbits.camera import compensate_flow, fit_camera_motion, stabilize_previous
from motionbits.config import MotionBitsConfig
from motionbits.evidence import (
    appearance_consistent, gradient_magnitude, motion_gain, pull_back)
from motionbits.flow import FlowBackend, forward_backward_error, make_flow, warp_nearest
from motionbits.graph import (
    apply_temporal_constraints,
    local_covariances,
    symmetric_graph,
    twist_noise_covariance,
    twist_edge_weights,
)
from motionbits.identity import match_ids, refine_history
from motionbits.masks import assign_pixels, fit_cluster_motions, remove_specks
from motionbits.merging import (
    MotionBitGroups, fit_affine, rigid_matrix, stillness_visible, touching_pairs, union_excess)
from motionbits.mcl import markov_cluster_coarse, normalize_rows
from motionbits.nodes import NodeGrid, sample_bilinear
from motionbits.objects import Instance, encode_rle
from motionbits.propagation import grid_seeds
from motionbits.retirement import Origin, moved_evidence
from motionbits.twists import fit_local_motions, refine_rigid_motion, se2_log
from motionbits.video import FrameSource, as_rgb_frame, iter_frames

__all__ = ["MotionBit", "MotionBitsResult", "MotionBitsSegmenter", "segment_video", "STAGES"]

#: Stage names of the per-frame timing report, in pipeline order.
STAGES = ("resize", "flow", "twists", "graph", "propagation", "clustering", "masks", "merging",
          "bookkeeping")


#: One MotionBit in one frame: the shared :class:`motionbits.Instance` with ``twist``,
#: ``moving``, ``first_moved`` and ``last_moved`` set (coordinates in input pixels; the
#: twist is zeros when it has no cluster this frame). ``update`` leaves ``mask`` unset
#: (the label map holds it): :meth:`MotionBitsResult.instances` attaches masks.
MotionBit = Instance


@dataclass
class MotionBitsResult:
    """Output of :meth:`MotionBitsSegmenter.update` for one frame.

    Attributes:
        frame_index: 0-based index of the frame in the stream.
        labels: (H, W) int32 at the input size; 0 = background, k > 0 = MotionBit k.
        motionbits: one record per id present in ``labels``.
        node_labels: (rows, cols) int32 MotionBit id of every grid node (0 = none).
        timings: milliseconds spent per stage (see ``STAGES``).
    """

    frame_index: int
    labels: np.ndarray
    motionbits: list[MotionBit]
    node_labels: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def ids(self) -> list[int]:
        return [mb.id for mb in self.motionbits]

    def instances(self, rle: bool = False) -> list[Instance]:
        """``motionbits`` with their (H, W) bool masks from ``labels`` (or COCO RLE when
        ``rle``; extra ``coco``); ``motionbits.to_supervision`` takes the result."""
        return [replace(mb, mask=None if rle else self.labels == mb.id,
                        rle=encode_rle(self.labels == mb.id) if rle else None)
                for mb in self.motionbits]


_STILL = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # the identity motion


def _gray(frame: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY).astype(np.float32)


class MotionBitsSegmenter:
    """Online, learning-free segmentation of moving rigid bodies.

    Feed frames one at a time with :meth:`update`; each call returns the MotionBits of that
    frame using only the frames seen so far. The first frame returns all-background labels.
    State is constant in size: the previous frame, the previous label map, one integer map
    of the label history and the largest past weight of each graph edge.

    Args:
        config: parameters; defaults are the paper's.
        flow: a flow backend ``flow(prev, next) -> (H, W, 2)``; default from ``config.flow``.

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
        self.config = config or MotionBitsConfig()
        self.flow = make_flow(flow if flow is not None else self.config.flow)
        self._ops = make_ops(self.config.backend)  # twist fits, propagation, MCL
        self._threads = ThreadpoolController()  # after make_ops: sees torch's OpenMP too
        self.reset()

    def reset(self) -> None:
        """Forget the stream: the next frame is treated as the first."""
        self.frame_index = -1
        self._input_size: tuple[int, int] | None = None
        self._work_size: tuple[int, int] | None = None
        self._grid: NodeGrid | None = None
        self._seeds: np.ndarray | None = None
        self._prev: np.ndarray | None = None
        self._labels: np.ndarray | None = None  # (h, w) int32 working-resolution labels
        self._history: np.ndarray | None = None  # (h, w) int32 meet of all label partitions
        self._earned: np.ndarray | None = None  # (h, w) int32 evidence of the labels (masks)
        self._past_max: np.ndarray | None = None  # (n, k) largest earlier edge weights
        self._noise_cov: np.ndarray | None = None  # (n, 3, 3) twist covariance of flow noise
        self._next_id = 1
        self._origins: dict[int, Origin] = {}  # id -> its birth frame and motion since
        self._tentative: set[int] = set()  # ids born at the last frame, not yet confirmed
        self._groups = MotionBitGroups(self.config.merge_agree, self.config.merge_disagree)
        self._first_moved: dict[int, int] = {}
        self._last_moved: dict[int, int] = {}
        self._timings: dict[str, float] = {}

    # ------------------------------------------------------------------ helpers
    @contextmanager
    def _stage(self, name: str) -> Iterator[None]:
        t0 = time.perf_counter()
        yield
        self._timings[name] = self._timings.get(name, 0.0) + 1000 * (time.perf_counter() - t0)

    def _start(self, frame: np.ndarray) -> None:
        h, w = frame.shape[:2]
        scale = self.config.max_side / max(h, w)
        self._input_size = (h, w)
        self._work_size = (max(8, int(round(h * scale))), max(8, int(round(w * scale))))
        hw, ww = self._work_size
        self._grid = NodeGrid.build(hw, ww, self.config.grid_side, self.config.k_neighbors)
        self._seeds = grid_seeds(self._grid.rows, self._grid.cols, self.config.seed_stride)
        self._labels = np.zeros((hw, ww), np.int32)
        self._history = np.zeros((hw, ww), np.int32)
        self._earned = np.zeros((hw, ww), np.int32)  # 1 = its MotionBit showed there
        self._past_max = np.zeros(self._grid.neighbors.shape)
        self._noise_cov = twist_noise_covariance(self._grid.points, self._grid.neighbors,
                                                 self.config.flow_noise)

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
            return self._update(frame)

    def _update(self, frame: np.ndarray) -> MotionBitsResult:
        frame = as_rgb_frame(frame, name=f"frame {self.frame_index + 1}")
        self._timings = {}
        if self._input_size is not None and frame.shape[:2] != self._input_size:
            raise ValueError(
                f"frame {self.frame_index + 1} is {frame.shape[1]}x{frame.shape[0]} but the stream "
                f"started at {self._input_size[1]}x{self._input_size[0]}; call reset() for a new video"
            )
        self.frame_index += 1
        if self._input_size is None:
            self._start(frame)
        with self._stage("resize"):
            cur = self._to_work(frame)
        if self._prev is None:
            self._prev = cur
            return self._empty_result()
        cfg, grid = self.config, self._grid
        with self._stage("flow"):
            flow_fwd = self.flow(self._prev, cur)
            flow_back = self.flow(cur, self._prev)
            # pixels whose backward target leaves the image come back inf or nan (remap
            # interpolates the inf border): treat both as "no reliable flow"
            fb_err = np.nan_to_num(forward_backward_error(flow_back, flow_fwd),
                                   nan=1e3, posinf=1e3)
            # last frame's labels and label history, carried to this frame
            cur_g, prev_g = _gray(cur), _gray(self._prev)
            raw_prev_g = prev_g
            pulled = pull_back(prev_g, flow_back)
            gradient = gradient_magnitude(cur_g)
            # a carried label holds a pixel only where the flow is consistent both ways and
            # its correspondence explains the pixel's appearance: uncovered background
            # does not inherit the label of the body that uncovered it
            prior_valid = (fb_err < cfg.fb_sigma) & appearance_consistent(
                cur_g, pulled, gradient, tolerance=cfg.carry_tolerance,
                gradient_gain=cfg.carry_gradient)
            carried = warp_nearest(np.dstack([self._labels, self._history, self._earned]),
                                   flow_back)
            prior, history, earned = carried[..., 0], carried[..., 1], carried[..., 2] > 0

        with self._stage("twists"):
            pts = grid.points
            ix = np.clip(np.round(pts).astype(np.int64), 0, [grid.width - 1, grid.height - 1])
            hist_nodes = history[ix[:, 1], ix[:, 0]]
            prior_nodes = np.where(prior_valid[ix[:, 1], ix[:, 0]], prior[ix[:, 1], ix[:, 0]], 0)
            seen_pts = pts + sample_bilinear(flow_back, pts)  # where the nodes came from
            node_err = sample_bilinear(np.minimum(fb_err, 1e3)[..., None], pts)[:, 0]
            reliability = np.exp(-((node_err / cfg.fb_sigma) ** 2))
            # camera motion compensation: motion is measured against the dominant motion
            # (flow_m, prev_m); label maps are still carried with the true flow
            flow_m, prev_m, back_pts, cam = flow_back, self._prev, seen_pts, None
            if cfg.camera_support < 1.0:
                cam = fit_camera_motion(pts, seen_pts, reliability > 0.5,
                                        support=cfg.camera_support,
                                        threshold=cfg.camera_threshold,
                                        min_shift=cfg.camera_min_shift)
                if cam is not None:
                    flow_m = compensate_flow(flow_back, cam)
                    prev_m = stabilize_previous(self._prev, cam)
                    back_pts = pts + sample_bilinear(flow_m, pts)
            motions = fit_local_motions(
                pts, back_pts, grid.neighbors, reliability, cfg.ransac_threshold,
                dtype=self._dtype, nodes=None if cfg.exact else self._nodes_to_fit(
                    back_pts - pts, prior_nodes), fit_fn=self._ops.fit_neighbourhoods)

        with self._stage("graph"):
            cov = local_covariances(motions.twist, grid.neighbors, self._noise_cov)
            raw = twist_edge_weights(motions.twist, grid.neighbors, cov)
            past = self._project_past_max(seen_pts)
            weights = apply_temporal_constraints(raw, grid.neighbors, hist_nodes, past)
            self._past_max = np.maximum(past, raw)
            # eq. 4: a node belongs to the moving set if it moves now or was part of a
            # MotionBit at the last frame; enclosed holes (e.g. near a centre of rotation,
            # where points barely move but share the body's twist) are filled.
            active = (motions.displacement > cfg.move_threshold) | (prior_nodes != 0)
            active = ndimage.binary_fill_holes(active.reshape(grid.rows, grid.cols)).ravel()
            w = symmetric_graph(weights, grid.neighbors, keep=active)
            active_idx = np.flatnonzero(active)

        with self._stage("propagation"):
            # W is block-diagonal over its connected components and paint never crosses
            # between them, so each component is propagated (and clustered) on its own
            seed_mask = np.zeros(grid.n, bool)
            seed_mask[self._seeds] = True
            n_comp, comp = connected_components(w, directed=False)
            seeds = np.flatnonzero(seed_mask[active_idx])
            # number the seeds within their component: one column per seed of the largest
            seed_comp = comp[seeds]
            order = np.argsort(seed_comp, kind="stable")
            starts = np.searchsorted(seed_comp[order], seed_comp[order])
            classes = np.empty(len(seeds), np.int64)
            classes[order] = np.arange(len(seeds)) - starts
            b = self._ops.propagate_labels(w, seeds, cfg.propagation_iters, cfg.reseed_every,
                                           dtype=self._dtype, classes=classes)
            n_seeds = np.bincount(seed_comp, minlength=n_comp)

        with self._stage("clustering"):
            painted = b.sum(axis=1) > 0
            painted_total = int(painted.sum())
            node_cluster = np.zeros(grid.n, np.int64)
            members_of = np.split(np.argsort(comp, kind="stable"),
                                  np.cumsum(np.bincount(comp, minlength=n_comp))[:-1]
                                  ) if n_comp else []
            for c, members in enumerate(members_of):
                cluster = self._cluster(b[members, :n_seeds[c]], w, members,
                                        active_idx[members], painted_total)
                node_cluster[active_idx[members]] = cluster + node_cluster.max()

        with self._stage("masks"):
            if prev_m is not self._prev:  # the camera-stabilised frame ("nothing moved");
                prev_g = _gray(prev_m)  # pulling it back along flow_m gives ``pulled`` again
            # computed only if some cluster is a candidate for a new MotionBit
            win = max(3, int(round(max(grid.cell))) | 1)
            evidence = cache(lambda: motion_gain(cur_g, prev_g, pulled, win)[ix[:, 1], ix[:, 0]])
            first_new, unconfirmed = self._next_id, self._tentative
            node_ids, ids, thetas, trans = self._identify(
                node_cluster, motions.displacement, prior[ix[:, 1], ix[:, 0]], pts, back_pts,
                reliability,
                evidence)
            kept = np.setdiff1d(np.unique(prior[prior_valid & (prior > 0)]), ids)
            kept = kept[~np.isin(kept, list(unconfirmed))]  # born last frame, not moving now
            labels, earned = assign_pixels(
                grid, node_ids, ids, thetas, trans, flow_m, cur_g, prev_g,
                prior, prior_valid, np.minimum(gradient / cfg.flow_texture, 1.0), earned,
                bonus=cfg.prior_bonus, photo_weight=cfg.photo_weight,
                evidence=cfg.pixel_evidence, kept=kept, ambiguous=cfg.move_threshold)
            cw, ch = grid.cell
            labels = remove_specks(labels, min_area=int(np.ceil(2 * cw * ch)))

        with self._stage("merging"):
            moving = self._record_motion(node_ids, ids, thetas, trans, pts)
            # the twists reported and merged: each moving MotionBit's motion refined on its
            # own pixels (flow reads rotations low)
            inner = cv2.erode(labels.astype(np.float32), np.ones((5, 5), np.uint8))
            for k, lab in enumerate(ids):
                if lab in moving:
                    thetas[k], trans[k] = refine_rigid_motion(cur_g, prev_g, inner == lab,
                                                              thetas[k], trans[k])
            own = {int(i): rigid_matrix(th, t) for i, th, t in zip(ids, thetas, trans)}
            reach = int(np.ceil(max(grid.cell)))
            # born out of pixels that were in view and had never been in a MotionBit
            margin = 2 * max(grid.cell)
            in_view = np.all((seen_pts >= margin) & (seen_pts < np.array(
                [grid.width, grid.height]) - margin), axis=1)
            born = {int(i) for i in ids[ids >= first_new]
                    if np.mean((hist_nodes == 0) & in_view, where=node_ids == i) > 0.5}
            for a, b in touching_pairs(labels, reach=reach):
                if self._groups.known(a, b):
                    continue
                for x, y in ((a, b), (b, a)):
                    # x was born out of pixels that had never been in a MotionBit while y
                    # moved, and y's motion would have shown on them: a different body (the
                    # pushed block is not the gripper that pushes it)
                    if x in born and y < first_new and y in own and y in moving:
                        if stillness_visible(labels, x, own[y], cur_g) > cfg.merge_disagree:
                            self._groups.forbid(x, [y])
                if self._groups.known(a, b) or (a not in own and b not in own):
                    continue
                sel = (node_ids == a) | (node_ids == b)
                union = fit_affine(pts[sel], back_pts[sel], reliability[sel])
                # a member without motion this frame (it stopped) stands still; standing
                # still beside a mover can show that they differ, never that they agree
                excess = union_excess(labels, a, b, own.get(a, _STILL), own.get(b, _STILL),
                                      union, cur_g, prev_g)
                if (a in own and b in own) or excess > cfg.merge_disagree:
                    self._groups.observe(a, b, excess)
            labels = self._retire(labels, ids, thetas, trans, first_new, cam, raw_prev_g, cur_g)
            rep = self._groups.representatives(np.unique(labels[labels > 0]))
            # a MotionBit born this frame is shown once it moves again, or as part of a
            # group that is already shown
            shown = {r for i, r in rep.items() if i not in self._tentative}
            rep = {i: r if r in shown else 0 for i, r in rep.items()}

        with self._stage("bookkeeping"):
            self._history = refine_history(history, labels, margin=int(np.ceil(max(grid.cell))))
            self._labels = labels
            self._earned = (earned & (labels > 0)).astype(np.int32)
            self._prev = cur
            result = self._result(labels, node_ids, ids, thetas, trans, moving, rep)
        result.timings = dict(self._timings)
        return result

    def _nodes_to_fit(self, node_flow: np.ndarray, prior_nodes: np.ndarray) -> np.ndarray:
        """Fast path: the nodes whose local twist can matter this frame.

        A node enters the moving set if its fitted displacement exceeds the threshold, if
        it was in a MotionBit, or if it lies in a hole of that set; the graph then reads
        the twists of its neighbourhood. So: nodes whose own flow exceeds half the
        threshold or that were in a MotionBit, grown by two rings of the grid (their
        neighbourhoods, and the neighbourhoods of those), with holes filled. Elsewhere
        nothing moves and a rigid fit only returns the flow's own translation.
        """
        g, cfg = self._grid, self.config
        seed = (np.hypot(node_flow[:, 0], node_flow[:, 1]) > 0.5 * cfg.move_threshold) | (
            prior_nodes != 0)
        grown = ndimage.binary_dilation(seed.reshape(g.rows, g.cols), np.ones((5, 5), bool))
        return np.flatnonzero(ndimage.binary_fill_holes(grown))

    def _project_past_max(self, back_pts: np.ndarray) -> np.ndarray:
        """Largest earlier weight of each current edge, read from the graph of the previous
        frame at the nodes nearest to where the edge's endpoints came from."""
        grid = self._grid
        src = grid.nearest_node(back_pts)
        si = src[:, None]
        sj = src[grid.neighbors]
        hit = grid.neighbors[si[:, 0]][:, None, :] == sj[:, :, None]  # (n, k, k)
        vals = np.where(hit, self._past_max[si[:, 0]][:, None, :], 0.0)
        return vals.max(axis=2)

    @property
    def _dtype(self) -> type:
        return np.float64 if self.config.exact else np.float32

    def _cluster(self, b: np.ndarray, w, members: np.ndarray, nodes: np.ndarray,
                 painted_total: int) -> np.ndarray:
        """Cluster indices 1..K of the nodes ``members`` (rows of ``w``; grid nodes ``nodes``)
        of one component of the graph ``w``: MCL on their rows of B that received paint
        (pruning relative to ``painted_total``, the painted nodes of the whole frame; on
        representatives if the fast path's ``mcl_max_items`` is exceeded); nodes that no
        seed reached are grouped by graph connectivity."""
        m = b.shape[0]
        out = np.zeros(m, np.int64)
        if m == 0:
            return out
        painted = b.sum(axis=1) > 0
        cfg = self.config
        if painted.any():
            bh = normalize_rows(b[painted])
            node = nodes[painted]
            lab, _ = markov_cluster_coarse(
                bh, np.stack([node // self._grid.cols, node % self._grid.cols], axis=1),
                len(bh) if cfg.exact else cfg.mcl_max_items, expansion=cfg.mcl_expansion,
                inflation=cfg.mcl_inflation, prune=cfg.mcl_prune, max_iters=cfg.mcl_max_iters,
                stable_iters=None if cfg.exact else cfg.mcl_stable_iters,
                prune_total=painted_total, dtype=self._dtype, block_fn=self._ops.mcl_block)
            out[painted] = lab + 1
        if not painted.any():  # a component without seeds: connected, so one group
            out[:] = 1
        elif not painted.all():
            rest = members[~painted]
            sub = w[rest][:, rest]
            _, comp = connected_components(sub, directed=False)
            out[~painted] = out.max() + 1 + comp
        return out

    def _identify(self, node_cluster, displacement, prior_nodes, pts, back_pts, reliability,
                  evidence):
        """Drop noise clusters, give each cluster a stable id and fit its motion.

        A cluster continues the earlier MotionBit it overlaps most (Hungarian on IoU); a
        cluster that continues none is a new MotionBit only if it moves now (eq. 4), which
        keeps static leftovers of a body's old place from becoming bodies of their own --
        and only if its flow explains its images better than "static" (``evidence()``, grey
        levels per node, averaged over the cluster), which keeps textureless regions with
        flow smeared in from a moving neighbour from becoming bodies.
        """
        cfg = self.config
        counts = np.bincount(node_cluster, minlength=1)
        big = np.flatnonzero(counts >= cfg.min_cluster_nodes)
        big = big[big > 0]
        remap = np.zeros(len(counts), np.int64)
        remap[big] = np.arange(1, len(big) + 1)
        cluster = remap[node_cluster]
        matched = match_ids(cluster, prior_nodes, len(big), cfg.match_iou)
        grid = cluster.reshape(self._grid.rows, self._grid.cols)
        # a node is interior iff its 3x3 neighbourhood holds one cluster value only
        interior = (ndimage.maximum_filter(grid, 3, mode="nearest")
                    == ndimage.minimum_filter(grid, 3, mode="nearest")).ravel()
        has_interior = np.bincount(cluster[interior], minlength=len(big) + 1) > 0
        ids = []
        newborn = set()
        for c in range(1, len(big) + 1):
            sel = cluster == c
            moves = np.median(displacement[sel]) > cfg.move_threshold
            if c in matched:
                i = matched[c]
                # a MotionBit born last frame stands only if it visibly moves again now
                ids.append(i if i not in self._tentative or (
                    moves and np.mean(evidence()[sel]) > cfg.motion_evidence) else 0)
            elif has_interior[c] and moves and np.mean(evidence()[sel]) > cfg.motion_evidence:
                ids.append(self._next_id)
                newborn.add(self._next_id)
                self._next_id += 1
            else:
                ids.append(0)
        self._tentative = newborn
        ids = np.asarray(ids, np.int64)
        node_ids = np.concatenate([[0], ids])[cluster]
        ids = ids[ids > 0]
        thetas, trans = fit_cluster_motions(pts, back_pts, reliability, node_ids, ids,
                                            cfg.ransac_threshold)
        return node_ids, ids, thetas, trans

    def _retire(self, labels, ids, thetas, trans, first_new, cam, prev_gray, cur_gray):
        """Advance every MotionBit's origin by this frame's motions and retire those whose
        pixels the static world explains better than their own accumulated motion
        (:mod:`motionbits.retirement`); returns ``labels`` without them."""
        world = np.eye(3) if cam is None else cam
        own = {int(i): world @ np.vstack([rigid_matrix(th, t), [0.0, 0.0, 1.0]])
               for i, th, t in zip(ids, thetas, trans)}
        present = set(np.unique(labels[labels > 0]).tolist())
        self._origins = {i: o for i, o in self._origins.items() if i in present}
        out = labels
        for i in sorted(present):
            if i >= first_new:
                self._origins[i] = Origin(prev_gray, np.eye(3), np.eye(3))
            origin = self._origins.get(i)
            if origin is None:
                continue
            origin.advance(own.get(i, world), world)
            gain = moved_evidence(origin, cur_gray, labels == i, 2.0)
            if gain < -self.config.retire_margin:
                out = np.where(out == i, 0, out)
                del self._origins[i]
        return out

    def _record_motion(self, node_ids, ids, thetas, trans, pts) -> set[int]:
        """Ids whose fitted motion moves their nodes by more than ``move_threshold`` (mean)
        this frame; updates their first / last frame of motion."""
        moving = set()
        for lab, th, t in zip(ids, thetas, trans):
            c, s = np.cos(th), np.sin(th)
            p = pts[node_ids == lab]
            moved = p @ np.array([[c, s], [-s, c]]) + t - p
            if float(np.mean(np.linalg.norm(moved, axis=1))) > self.config.move_threshold:
                moving.add(int(lab))
                self._first_moved.setdefault(int(lab), self.frame_index)
                self._last_moved[int(lab)] = self.frame_index
        return moving

    def _result(self, labels, node_ids, ids, thetas, trans, moving, rep) -> MotionBitsResult:
        """Records of the MotionBits shown: each group of merged ids under its oldest id,
        with the twist of its largest member that has a motion this frame."""
        grid = self._grid
        h, w = self._input_size
        scale = w / grid.width, h / grid.height
        lut = np.arange(max([int(labels.max()), *rep.keys(), 0]) + 1)
        for i, r in rep.items():
            lut[i] = r
        out = lut[labels].astype(np.int32)
        node_out = lut[np.minimum(node_ids, len(lut) - 1)] * (node_ids < len(lut))
        members: dict[int, list[int]] = {}
        for i, r in rep.items():
            members.setdefault(r, []).append(i)
        counts = np.bincount(node_ids, minlength=len(lut))
        twists = {int(i): -se2_log(th, t) for i, th, t in zip(ids, thetas, trans)}
        if (h, w) != out.shape:
            out = cv2.resize(out, (w, h), interpolation=cv2.INTER_NEAREST)
        records = []
        for index, box in enumerate(ndimage.find_objects(out)):
            if box is None:
                continue
            lab = index + 1
            group = members.get(lab, [lab])
            with_motion = [i for i in group if i in twists]
            tw = twists[max(with_motion, key=lambda i: counts[i])] if with_motion else np.zeros(3)
            first = [self._first_moved[i] for i in group if i in self._first_moved]
            last = [self._last_moved[i] for i in group if i in self._last_moved]
            ys, xs = np.nonzero(out[box] == lab)
            ys, xs = ys + box[0].start, xs + box[1].start
            records.append(MotionBit(
                id=lab, area=int(len(xs)),
                bbox=(box[1].start, box[0].start, box[1].stop, box[0].stop),
                centroid=(float(xs.mean()), float(ys.mean())),
                twist=(float(tw[0]), float(tw[1] * scale[0]), float(tw[2] * scale[1])),
                moving=any(i in moving for i in group),
                first_moved=min(first, default=self.frame_index),
                last_moved=max(last, default=self.frame_index),
            ))
        return MotionBitsResult(self.frame_index, out, records,
                                node_out.reshape(grid.rows, grid.cols).astype(np.int32))


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
    """
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    seg = MotionBitsSegmenter(config, flow=flow)
    for i, frame in enumerate(iter_frames(source)):
        if i % every == 0:
            yield seg.update(frame)
