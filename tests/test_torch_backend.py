"""The torch backend (MotionBitsConfig.backend="torch...") against the numpy path, on CPU."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from motionbits import MotionBitsConfig, MotionBitsSegmenter
from motionbits.backend import NUMPY_OPS, make_ops
from motionbits.eval import adjusted_rand_index
from motionbits.mcl import markov_cluster, normalized_similarity
from motionbits.nodes import NodeGrid
from motionbits.propagation import propagate_labels
from motionbits.twists import fit_local_motions

DTYPES = [np.float32, np.float64]


@pytest.fixture(scope="module")
def ops():
    pytest.importorskip("torch")
    return make_ops("torch:cpu")


# ------------------------------------------------------------------ selection and errors
def test_import_motionbits_does_not_import_torch():
    code = ("import sys, motionbits, motionbits.segmenter, motionbits.backend, "
            "motionbits.torch_ops; from motionbits import MotionBitsSegmenter, "
            "MotionBitsConfig; MotionBitsSegmenter(MotionBitsConfig(n_nodes=64)); "
            "assert 'torch' not in sys.modules, 'torch imported'")
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("backend", ["torch:gpu", "cuda", "Torch", "torch:", "torch:cuda:x",
                                     "numpy:cpu", "", None])
def test_bad_backend_strings(backend):
    with pytest.raises(ValueError, match="choose one of .*numpy.*torch:cpu.*torch:cuda"):
        MotionBitsConfig(backend=backend)


@pytest.mark.parametrize("backend", ["numpy", "torch", "torch:cpu", "torch:cuda", "torch:cuda:1"])
def test_good_backend_strings_validate_without_torch(backend):
    assert MotionBitsConfig(backend=backend).backend == backend  # nothing imported yet


def test_torch_backend_without_torch_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # `import torch` now raises ImportError
    with pytest.raises(ImportError, match="pip install torch"):
        MotionBitsSegmenter(MotionBitsConfig(n_nodes=64, backend="torch:cpu"))


def test_cuda_without_gpu_is_a_clear_error():
    torch = pytest.importorskip("torch")
    if torch.cuda.is_available():
        pytest.skip("a GPU is present")
    with pytest.raises(RuntimeError, match="CUDA"):
        MotionBitsSegmenter(MotionBitsConfig(n_nodes=64, backend="torch:cuda"))
    # "torch" alone falls back to the CPU
    assert MotionBitsSegmenter(MotionBitsConfig(n_nodes=64, backend="torch"))._ops.name == "torch:cpu"


def test_numpy_backend_uses_the_numpy_functions():
    assert MotionBitsSegmenter(MotionBitsConfig(n_nodes=64))._ops is NUMPY_OPS


# ------------------------------------------------------------------ the three ops
def _motion_inputs(seed=0):
    rng = np.random.default_rng(seed)
    grid = NodeGrid.build(120, 160, 20, 5)
    pts = grid.points.astype(np.float64)
    th = np.where(pts[:, 0] < 80, 0.05, -0.03)  # two rigid motions
    c, s = np.cos(th), np.sin(th)
    back = np.stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]], 1)
    back += rng.normal(0, 0.1, back.shape) + [1.5, -0.7]
    out = rng.random(grid.n) < 0.1
    back[out] += rng.normal(0, 3, (out.sum(), 2))  # outliers
    weights = rng.uniform(0.0, 1.0, grid.n)
    weights[rng.random(grid.n) < 0.05] = 0.0
    return grid, pts, back, weights


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("subset", [False, True])
def test_twists_match_numpy(ops, dtype, subset):
    grid, pts, back, weights = _motion_inputs()
    nodes = np.arange(0, grid.n, 3) if subset else None
    ref = fit_local_motions(pts, back, grid.neighbors, weights, 0.5, dtype=dtype, nodes=nodes)
    got = fit_local_motions(pts, back, grid.neighbors, weights, 0.5, dtype=dtype, nodes=nodes,
                            fit_fn=ops.fit_neighbourhoods)
    np.testing.assert_array_equal(got.inliers, ref.inliers)
    for name in ("twist", "angle", "trans", "displacement"):
        a, b = getattr(got, name), getattr(ref, name)
        assert a.dtype == b.dtype == np.float64
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9, err_msg=name)


def test_twists_empty(ops):
    grid, pts, back, weights = _motion_inputs()
    idx = np.zeros((0, 6), np.int64)
    ang, trans, inl = ops.fit_neighbourhoods(pts, back, idx, weights, 0.5, np.float32)
    assert ang.shape == (0,) and trans.shape == (0, 2) and inl.shape == (0, 6)


def _random_graph(rng, m, density=0.05):
    w = sp.random(m, m, density=density, random_state=rng, format="csr")
    w = (w + w.T).tocsr()
    w.data = np.abs(w.data)
    return w


@pytest.mark.parametrize("dtype", DTYPES)
def test_propagation_matches_numpy(ops, dtype):
    rng = np.random.default_rng(1)
    keep = np.ones(200)
    keep[5] = 0  # an isolated node keeps a zero row
    w = (sp.diags(keep) @ _random_graph(rng, 200) @ sp.diags(keep)).tocsr()
    seeds = np.array([0, 17, 42, 99, 150, 5])
    classes = np.array([0, 1, 2, 0, 1, 3])
    for cls in (None, classes):
        ref = propagate_labels(w, seeds, 30, 5, dtype=dtype, classes=cls)
        got = ops.propagate_labels(w, seeds, 30, 5, dtype=dtype, classes=cls)
        assert got.dtype == ref.dtype == np.dtype(dtype) and got.shape == ref.shape
        rtol = 1e-5 if dtype == np.float32 else 1e-12
        np.testing.assert_allclose(got, ref, rtol=rtol, atol=rtol * np.abs(ref).max())


def test_propagation_without_seeds(ops):
    w = _random_graph(np.random.default_rng(2), 20)
    out = ops.propagate_labels(w, np.zeros(0, np.int64), 10, 5, dtype=np.float32)
    assert out.shape == (20, 0) and out.dtype == np.float32


def _clustered_similarity(rng, m, k):
    groups = rng.integers(0, k, m)
    b = rng.uniform(0, 0.3, (m, 4 * k)) + 2.0 * (np.arange(4 * k)[None] // 4 == groups[:, None])
    return normalized_similarity(b)


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mcl_matches_numpy(ops, dtype, seed):
    rng = np.random.default_rng(seed)
    x = _clustered_similarity(rng, 120, 4)
    x[:40, 40:] = x[40:, :40] = 0  # two blocks
    stable = None if dtype == np.float64 else 2
    kw = dict(expansion=2, inflation=1.15, prune=0.6, stable_iters=stable, dtype=dtype,
              prune_total=150)
    ref, _ = markov_cluster(x, **kw)
    got, _ = markov_cluster(x, block_fn=ops.mcl_block, **kw)
    assert len(np.unique(ref)) > 1
    np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("dtype", DTYPES)
def test_mcl_block_matches_numpy_with_multiplicity(ops, dtype):
    from motionbits.mcl import _mcl_block

    rng = np.random.default_rng(3)
    x = _clustered_similarity(rng, 60, 3)
    mult = rng.integers(1, 4, 60).astype(np.float64)
    args = (mult, 2, 1.3, 0.6 / mult.sum(), 100, None, dtype)
    x_copy = x.copy()
    ref, _ = _mcl_block(x, *args)
    got, _ = ops.mcl_block(x, *args)
    np.testing.assert_array_equal(x, x_copy)  # the input is not modified
    np.testing.assert_array_equal(got, ref)
    assert ops.mcl_block(np.ones((1, 1)), *args)[0].tolist() == [0]


# ------------------------------------------------------------------ whole segmenter
@pytest.fixture(scope="module")
def small_clip():
    from motionbits.synth import demo_clip

    return demo_clip(n_frames=5, size=(120, 160))


@pytest.mark.parametrize("exact", [False, True])
def test_segmenter_torch_cpu_gives_numpy_labels(ops, small_clip, exact):
    maps = {}
    for backend in ("numpy", "torch:cpu"):
        seg = MotionBitsSegmenter(MotionBitsConfig(n_nodes=900, exact=exact, backend=backend))
        maps[backend] = [seg.update(f).labels for f in small_clip.frames]
    assert any(m.any() for m in maps["numpy"])  # something was segmented
    for ref, got in zip(maps["numpy"], maps["torch:cpu"]):
        # identical in practice; a partition tie (e.g. a block of identical rows) can be
        # split differently by rounding, hence the ARI bound
        assert np.array_equal(ref, got) or adjusted_rand_index(ref, got) >= 0.99
