"""Baseline (b): multi-model affine motion segmentation by sequential RANSAC.

Classic motion segmentation (Torr 1998; Vidal et al. 2005, "Multibody" / sequential RANSAC):
on the moving pixels of the last frame, each pixel p has a correspondence q = p + D(p) in
the first frame (flow chained over the clip, ``motion_evidence``). Repeatedly fit an affine
map q = A p + b by RANSAC (3-point samples drawn locally so small bodies are found, all
hypotheses scored at once), keep the model with most inliers, remove them, and repeat
until few points remain. Every moving pixel then takes the model with the smallest residual
(if below ``2 * inlier_px``); each model's pixels are split into connected components.
"""

from __future__ import annotations

import numpy as np

from motionbits.baselines.flow_threshold import clean_components
from motionbits.baselines.motion_evidence import motion_evidence
from motionbits.flow import DISFlow, FlowBackend

__all__ = ["AffineMotionClusters", "fit_affine", "sequential_ransac"]


def fit_affine(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Least-squares affine q ~ [p, 1] @ M; p, q (N, 2) -> M (3, 2)."""
    X = np.concatenate([p, np.ones((len(p), 1))], axis=1)
    return np.linalg.lstsq(X, q, rcond=None)[0]


def sequential_ransac(p: np.ndarray, q: np.ndarray, rng: np.random.Generator, *,
                      inlier_px: float = 1.5, hypotheses: int = 256, max_models: int = 8,
                      min_inliers: int = 30, radius: float = 40.0) -> list[np.ndarray]:
    """Affine models (each (3, 2)) explaining ``q`` from ``p``, strongest first.

    Args:
        p, q: (N, 2) float point correspondences.
        inlier_px: residual below which a point supports a model.
        hypotheses: RANSAC samples per model.
        max_models, min_inliers: stopping rules.
        radius: the 2nd and 3rd points of a sample lie within this many px of the 1st.
    """
    models = []
    left = np.arange(len(p))
    while len(models) < max_models and len(left) >= min_inliers:
        P, Q = p[left], q[left]
        seeds = rng.integers(0, len(P), hypotheses)
        # Local samples: two more points near each seed (fall back to any point).
        others = np.empty((hypotheses, 2), np.int64)
        for h, s in enumerate(seeds):
            near = np.flatnonzero(np.abs(P - P[s]).max(axis=1) < radius)
            pool = near if len(near) >= 3 else np.arange(len(P))
            others[h] = rng.choice(pool, 2, replace=False)
        idx = np.concatenate([seeds[:, None], others], axis=1)  # (h, 3)
        X = np.concatenate([P[idx], np.ones((hypotheses, 3, 1))], axis=2)  # (h, 3, 3)
        ok = np.abs(np.linalg.det(X)) > 1e-3
        if not ok.any():
            break
        M = np.linalg.solve(X[ok], Q[idx[ok]])  # (h', 3, 2)
        Xall = np.concatenate([P, np.ones((len(P), 1))], axis=1)
        res = np.linalg.norm(np.einsum("nk,hkc->hnc", Xall, M) - Q[None], axis=2)
        support = (res < inlier_px).sum(axis=1)
        best = int(np.argmax(support))
        if support[best] < min_inliers:
            break
        inl = res[best] < inlier_px
        model = fit_affine(P[inl], Q[inl])
        inl = np.linalg.norm(Xall @ model - Q, axis=1) < inlier_px
        if inl.sum() < min_inliers:
            break
        models.append(model)
        left = left[~inl]
    return models


class AffineMotionClusters:
    """Sequential-RANSAC affine motion clusters of the moving pixels.

    Args:
        threshold: px per frame for a pixel to count as moving.
        inlier_px: RANSAC inlier residual in px (on displacements chained over the clip).
        stride: sample every ``stride``-th pixel for model fitting.
        min_area: smallest kept component, fraction of the image.
        seed: RANSAC random seed (deterministic).
        flow: flow backend (default OpenCV DIS, MEDIUM).
    """

    def __init__(self, threshold: float = 1.0, inlier_px: float = 1.5, stride: int = 4,
                 min_area: float = 0.001, seed: int = 0, flow: FlowBackend | None = None) -> None:
        self.threshold, self.inlier_px, self.stride = float(threshold), float(inlier_px), int(stride)
        self.min_area, self.seed = float(min_area), int(seed)
        self.flow = flow or DISFlow("medium")

    def __call__(self, frames: list[np.ndarray]) -> np.ndarray:
        moved, disp = motion_evidence(frames, self.flow, self.threshold)
        moving = clean_components(moved, self.min_area) > 0
        h, w = moving.shape
        ys, xs = np.nonzero(moving)
        out = np.zeros((h, w), np.int32)
        if len(xs) == 0:
            return out
        pts = np.stack([xs, ys], axis=1).astype(np.float64)
        tgt = pts + disp[ys, xs].astype(np.float64)
        sub = ((xs % self.stride) == 0) & ((ys % self.stride) == 0)
        rng = np.random.default_rng(self.seed)
        models = sequential_ransac(pts[sub], tgt[sub], rng, inlier_px=self.inlier_px,
                                   min_inliers=max(10, int(self.min_area * h * w / self.stride ** 2)))
        if not models:
            return clean_components(moving, self.min_area)
        X = np.concatenate([pts, np.ones((len(pts), 1))], axis=1)
        res = np.stack([np.linalg.norm(X @ m - tgt, axis=1) for m in models], axis=1)
        best = res.argmin(axis=1)
        assigned = res[np.arange(len(best)), best] < 2 * self.inlier_px
        next_label = 1
        for k in range(len(models)):
            mask = np.zeros((h, w), bool)
            sel = assigned & (best == k)
            mask[ys[sel], xs[sel]] = True
            comps = clean_components(mask, self.min_area, open_px=1)
            n = comps.max()
            out[comps > 0] = comps[comps > 0] + next_label - 1
            next_label += n
        return out
