"""Torch versions of the three heavy steps of a frame (``MotionBitsConfig.backend="torch..."``).

- :meth:`TorchOps.fit_neighbourhoods`: the 15-pair RANSAC + weighted Kabsch of every node
  neighbourhood (:func:`motionbits.twists._fit_neighbourhoods`);
- :meth:`TorchOps.propagate_labels`: the R sparse diffusion steps
  (:func:`motionbits.propagation.propagate_labels`), a torch CSR matrix times a dense B;
- :meth:`TorchOps.mcl_block`: Markov clustering of one connected block
  (:func:`motionbits.mcl._mcl_block`), the products on the device, the attractor systems
  on the CPU from the column argmax.

Each has the signature and the semantics of its numpy counterpart -- numpy arrays in,
numpy arrays out, the same dtype rules (the scoring / iterate in ``dtype``, float32 on the
fast path, float64 when ``config.exact``) -- so the rest of the pipeline is unchanged. On
the CPU the results equal the numpy ones up to floating-point rounding (the libraries sum
in different orders), which the tests check gives the same labels.

torch is imported only when a :class:`TorchOps` is built, never by ``import motionbits``.
"""

from __future__ import annotations

import warnings
from itertools import combinations

import numpy as np

from motionbits.mcl import _by_first_appearance, _functional_components
from motionbits.propagation import row_stochastic

__all__ = ["TorchOps", "import_torch", "resolve_device"]


def import_torch():
    """The torch module, or an ImportError that says how to get it."""
    try:
        import torch
    except ImportError as exc:
        raise ImportError(
            "MotionBitsConfig(backend='torch...') needs PyTorch, which is not installed: "
            "pip install torch (or pip install 'motionbits[torch]'), or use backend='numpy'"
        ) from exc
    return torch


def resolve_device(backend: str):
    """torch.device of a ``backend`` string ("torch", "torch:cpu", "torch:cuda[:N]")."""
    torch = import_torch()
    if backend == "torch":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    prefix, _, name = backend.partition(":")
    if prefix != "torch" or not name:
        raise ValueError(f"not a torch backend: {backend!r}")
    device = torch.device(name)
    if device.type == "cuda":
        if not torch.cuda.is_available():
            raise RuntimeError(
                f"backend {backend!r} asks for CUDA, but torch.cuda.is_available() is False "
                f"(torch {torch.__version__}, no usable GPU or a CPU-only build); use "
                "backend='torch' (CUDA when present, else CPU) or 'torch:cpu'")
        count = torch.cuda.device_count()
        if device.index is not None and device.index >= count:
            raise RuntimeError(f"backend {backend!r}: there are only {count} CUDA device(s)")
    elif device.type != "cpu":
        raise ValueError(f"unsupported torch device in backend {backend!r}")
    return device


def _float32_threshold(threshold: float) -> np.float32:
    """The smallest float32 t >= ``threshold``: for float32 x, x < t iff x < threshold
    (numpy compares a float32 array with a float64 scalar in float64)."""
    t = np.float32(threshold)
    if float(t) < float(threshold):
        t = np.nextafter(t, np.float32(np.inf))
    return t


class TorchOps:
    """The heavy steps on one torch device (see the module docstring)."""

    def __init__(self, device) -> None:
        self.torch = import_torch()
        self.device = self.torch.device(device)

    def _dtype(self, dtype):
        return self.torch.float64 if np.dtype(dtype) == np.float64 else self.torch.float32

    def _tensor(self, a, dtype=None):
        """A fresh device tensor holding numpy ``a`` (cast in numpy, as the numpy path does)."""
        a = np.asarray(a) if dtype is None else np.asarray(a).astype(dtype)
        return self.torch.tensor(a, device=self.device)

    # ------------------------------------------------------------------ twists
    def fit_neighbourhoods(self, points, back_points, idx, weights, inlier_threshold, dtype):
        """:func:`motionbits.twists._fit_neighbourhoods` on the device."""
        torch = self.torch
        n, m = idx.shape
        if n == 0:
            return np.zeros(0), np.zeros((0, 2)), np.zeros((0, m), bool)
        it = self._tensor(idx, np.int64)
        p = self._tensor(points, dtype)[it]  # (n, m, 2)
        q = self._tensor(back_points, dtype)[it]
        w = self._tensor(weights, dtype)[it]  # (n, m)

        pairs = np.array(list(combinations(range(m), 2)))  # (P, 2)
        a = torch.as_tensor(pairs[:, 0], device=self.device)
        b = torch.as_tensor(pairs[:, 1], device=self.device)
        px, py, qx, qy = p[..., 0], p[..., 1], q[..., 0], q[..., 1]
        dpx, dpy = px[:, b] - px[:, a], py[:, b] - py[:, a]  # (n, P)
        dqx, dqy = qx[:, b] - qx[:, a], qy[:, b] - qy[:, a]
        theta = torch.atan2(dpx * dqy - dpy * dqx, dpx * dqx + dpy * dqy)
        c, s = torch.cos(theta), torch.sin(theta)  # (n, P)
        mpx, mpy = 0.5 * (px[:, a] + px[:, b]), 0.5 * (py[:, a] + py[:, b])
        tx = 0.5 * (qx[:, a] + qx[:, b]) - (c * mpx - s * mpy)
        ty = 0.5 * (qy[:, a] + qy[:, b]) - (s * mpx + c * mpy)
        c, s = c[..., None], s[..., None]  # (n, P, 1)
        pxe, pye = px[:, None, :], py[:, None, :]  # (n, 1, m)
        rx = c * pxe - s * pye + tx[..., None] - qx[:, None, :]  # (n, P, m)
        ry = s * pxe + c * pye + ty[..., None] - qy[:, None, :]
        r2 = rx * rx + ry * ry
        tau2 = inlier_threshold**2
        # MSAC cost, its pair-index tie-break added in float64 as numpy does
        cost = (w[:, None, :] * torch.clamp(r2, max=tau2)).sum(-1).to(torch.float64)
        cost = cost + 1e-9 * torch.arange(len(pairs), device=self.device, dtype=torch.float64)
        best = torch.argmin(cost, dim=1)
        r2_best = torch.gather(r2, 1, best[:, None, None].expand(n, 1, m))[:, 0]
        inliers = r2_best < tau2  # (n, m)
        fit_w = self._tensor(weights, np.float64)[it] * inliers
        none = fit_w.sum(1) <= 0
        fit_w[none] = 1.0
        ang, trans = self._kabsch(self._tensor(points, np.float64)[it],
                                  self._tensor(back_points, np.float64)[it], fit_w)
        return ang.cpu().numpy(), trans.cpu().numpy(), inliers.cpu().numpy()

    def _kabsch(self, p, q, w):
        """:func:`motionbits.twists.kabsch_2d` in torch: theta (n,), t (n, 2)."""
        torch = self.torch
        ws = w.sum(-1, keepdim=True)
        ws_safe = torch.where(ws > 0, ws, torch.ones_like(ws))
        pm = (w[..., None] * p).sum(-2) / ws_safe
        qm = (w[..., None] * q).sum(-2) / ws_safe
        pc = p - pm[..., None, :]
        qc = q - qm[..., None, :]
        cross = (w * (pc[..., 0] * qc[..., 1] - pc[..., 1] * qc[..., 0])).sum(-1)
        dot = (w * (pc[..., 0] * qc[..., 0] + pc[..., 1] * qc[..., 1])).sum(-1)
        theta = torch.atan2(cross, dot)
        c, s = torch.cos(theta), torch.sin(theta)
        t = torch.stack([qm[..., 0] - (c * pm[..., 0] - s * pm[..., 1]),
                         qm[..., 1] - (s * pm[..., 0] + c * pm[..., 1])], -1)
        return theta, t

    # ------------------------------------------------------------------ propagation
    def propagate_labels(self, w, seeds, iters, reseed_every, dtype=np.float64, classes=None):
        """:func:`motionbits.propagation.propagate_labels` on the device."""
        torch = self.torch
        m = w.shape[0]
        classes = np.arange(len(seeds)) if classes is None else np.asarray(classes)
        n_cls = int(classes.max()) + 1 if len(classes) else 0
        if m == 0 or n_cls == 0:
            out = np.zeros((m, n_cls), dtype)
            if n_cls:
                out[seeds, classes] = 1.0
            return out
        a = row_stochastic(w.tocsr()).astype(dtype).tocsr()
        a.sort_indices()
        with warnings.catch_warnings():  # "sparse CSR support is in beta"
            warnings.simplefilter("ignore", UserWarning)
            a_t = torch.sparse_csr_tensor(
                self._tensor(a.indptr, np.int64), self._tensor(a.indices, np.int64),
                self._tensor(a.data), size=(m, m), check_invariants=False)
        y = torch.zeros((m, n_cls), dtype=self._dtype(dtype), device=self.device)
        y[torch.as_tensor(np.asarray(seeds, np.int64), device=self.device),
          torch.as_tensor(classes.astype(np.int64), device=self.device)] = 1.0
        b = y.clone()
        for r in range(1, iters + 1):
            b = a_t @ b
            if r % reseed_every == 0:
                b += y
        return b.cpu().numpy()

    # ------------------------------------------------------------------ MCL
    def _attractors(self, m) -> np.ndarray:
        return _by_first_appearance(_functional_components(m.argmax(0).cpu().numpy()))

    def mcl_block(self, x, mult, expansion, inflation, threshold, max_iters, stable_iters, dtype,
                  factor=None):
        """:func:`motionbits.mcl._mcl_block` on the device."""
        torch = self.torch
        if x.shape[0] == 1:
            return np.zeros(1, np.int64), 0
        m = self._tensor(x, dtype)
        mult = self._tensor(mult, dtype)
        m.fill_diagonal_(1.0)

        def normalize(m):
            s = mult @ m
            return m / torch.where(s > 0, s, torch.ones_like(s))

        col_sums = mult @ m
        inv_sums = 1.0 / torch.where(col_sums > 0, col_sums, torch.ones_like(col_sums))
        m = m * inv_sums
        exact = np.dtype(dtype) == np.float64
        tol = 1e-9 if exact else 1e-6
        thr = float(threshold) if exact else float(_float32_threshold(threshold))
        labels = self._attractors(m)
        same = 0
        it = 0
        for it in range(1, max_iters + 1):
            prev = m
            if it == 1 and factor is not None and expansion == 2:
                # the low-rank first expansion of the numpy path: X D X = B^ (B^T D B^) B^T
                f = self._tensor(factor, dtype)
                inner = f.T @ (f * (mult * inv_sums)[:, None])
                m = (f @ inner) @ (f.T * inv_sums)
            else:
                for _ in range(expansion - 1):
                    live = torch.nonzero(m.any(dim=1)).squeeze(1)
                    if len(live) == m.shape[0]:
                        m = (m * mult) @ m
                    else:  # rows without mass stay zero: multiply only the others
                        nxt = torch.zeros_like(m)
                        nxt[live] = (m[live][:, live] * mult[live]) @ m[live]
                        m = nxt
            m = normalize(m.pow(inflation))
            if threshold > 0:
                m = normalize(m.masked_fill(m < thr, 0.0))
            if stable_iters is None:  # the reference: iterate until idempotent
                if (m - prev).abs().max().item() <= tol:
                    break
            else:
                new = self._attractors(m)
                same = same + 1 if np.array_equal(new, labels) else 0
                labels = new
                if same >= stable_iters:
                    break
        return self._attractors(m), it
