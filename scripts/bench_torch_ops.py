"""Micro-timing of the heavy steps: numpy vs a torch backend (not a test).

    PYTHONPATH=. python scripts/bench_torch_ops.py [--backend torch:cpu] [--n 10000] [--mcl 1000] [--threads 1]

Times each op on generated inputs at n nodes (twists: every node fitted, as with exact=True;
propagation: a 5-NN grid graph, one component, ~0.04 n seeds) and MCL on one dense block of
``--mcl`` nodes (a full n-node block is a dense n x n problem), in float32 and float64, and
checks that the outputs agree.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from motionbits.backend import NUMPY_OPS, make_ops
from motionbits.graph import symmetric_graph
from motionbits.mcl import normalized_similarity
from motionbits.nodes import NodeGrid
from motionbits.propagation import grid_seeds


def best_of(fn, repeat):
    out, best = None, np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best * 1000, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--backend", default="torch:cpu")
    ap.add_argument("--n", type=int, default=10_000)
    ap.add_argument("--mcl", type=int, default=1000, help="nodes of the MCL block")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0, help="torch CPU threads (0: torch's default)")
    args = ap.parse_args()
    if args.threads:
        import torch

        torch.set_num_threads(args.threads)
    warnings.filterwarnings("ignore")
    ops = make_ops(args.backend)
    rng = np.random.default_rng(0)
    side = int(round(np.sqrt(args.n)))
    grid = NodeGrid.build(480, 640, side, 5)
    n = grid.n
    pts = grid.points.astype(np.float64)
    # two rigid motions plus flow noise and outliers
    th = np.where(pts[:, 0] < 320, 0.02, -0.01)
    c, s = np.cos(th), np.sin(th)
    back = np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]], 1) + 1.5
    back += rng.normal(0, 0.1, back.shape)
    back[rng.random(n) < 0.05] += rng.normal(0, 3, (1, 2))
    weights = rng.uniform(0.3, 1.0, n)
    idx = np.concatenate([np.arange(n)[:, None], grid.neighbors], 1)
    w = symmetric_graph(rng.uniform(0.05, 1.0, grid.neighbors.shape), grid.neighbors)
    seeds = grid_seeds(grid.rows, grid.cols, 5)
    k = args.mcl
    groups = rng.integers(0, 6, k)
    b = rng.uniform(0, 0.05, (k, 60)) + (np.arange(60)[None, :] // 10 == groups[:, None])
    x = normalized_similarity(b)
    mult = np.ones(k)
    import torch

    print(f"backend {ops.name} ({torch.get_num_threads()} torch threads), n = {n} nodes, {len(seeds)} seeds, MCL block {k} nodes, "
          f"best of {args.repeat}")
    for dtype in (np.float32, np.float64):
        name = np.dtype(dtype).name
        thr = 0.6 / k
        runs = {
            "twists": lambda o: o.fit_neighbourhoods(pts, back, idx, weights, 0.5, dtype),
            "propagation": lambda o: o.propagate_labels(w, seeds, 100, 5, dtype=dtype),
            "mcl": lambda o: o.mcl_block(x, mult, 2, 1.15, thr, 100,
                                         2 if dtype == np.float32 else None, dtype),
        }
        for op, run in runs.items():
            t_np, out_np = best_of(lambda: run(NUMPY_OPS), args.repeat)
            t_t, out_t = best_of(lambda: run(ops), args.repeat)
            if op == "twists":
                same = all(np.allclose(a, b, atol=1e-6) for a, b in zip(out_np, out_t))
            elif op == "propagation":
                same = np.allclose(out_np, out_t, rtol=1e-4, atol=1e-6)
            else:
                same = np.array_equal(out_np[0], out_t[0])
            print(f"{op:12s} {name}: numpy {t_np:8.1f} ms   {ops.name} {t_t:8.1f} ms   "
                  f"x{t_np / t_t:5.2f}   same: {same}")


if __name__ == "__main__":
    main()
