"""Benchmark methods: a registry of plug-ins ``frames -> last-frame label map``.

Built in (no model weights): ``flow-cc`` (flow threshold + connected components),
``affine-ransac`` (sequential-RANSAC affine motion clusters), ``per-colour`` (connected
regions of similar colour in the last frame, no motion), ``motionbits`` (the
segmenter, imported when first used), ``motionbits-exact`` (its exact reference path) and
``motionbits-oracle-flow`` (the segmenter on a generated scene's exact flow). Add more with
:func:`register_method` or an entry point in the group ``motionbits.methods``. A method
with a true attribute ``needs_scene`` is called as ``method(frames, scene=folder)``.
"""

from motionbits.baselines.registry import (
    Method, MethodInfo, available_methods, make_method, register_method,
)


def _flow_cc(**kw):
    from motionbits.baselines.flow_threshold import FlowThresholdCC
    return FlowThresholdCC(**kw)


def _affine(**kw):
    from motionbits.baselines.affine_clusters import AffineMotionClusters
    return AffineMotionClusters(**kw)


def _motionbits(**kw):
    from motionbits.baselines.motionbits_method import MotionBitsMethod
    return MotionBitsMethod(**kw)


def _per_colour(**kw):
    from motionbits.baselines.per_colour import PerColourSegmenter
    return PerColourSegmenter(**kw)


def _oracle_flow(**kw):
    from motionbits.baselines.oracle_flow import OracleFlowMotionBits
    return OracleFlowMotionBits(**kw)


register_method("flow-cc", _flow_cc, "DIS flow magnitude > 1 px at any time + connected components")
register_method("affine-ransac", _affine, "sequential-RANSAC affine motion clusters on chained DIS flow")
register_method("per-colour", _per_colour,
                "connected regions of similar colour in the last frame (appearance only, no motion)")
register_method("motionbits", _motionbits, "MotionBits (motionbits.segment_video), paper defaults")
register_method("motionbits-exact", lambda **kw: _motionbits(**{"exact": True, **kw}),
                "MotionBits, exact reference path (float64, MCL until idempotent)")
register_method("motionbits-oracle-flow", _oracle_flow,
                "MotionBits on the scene's exact flow (scenes from motionbits synth --flow)")

__all__ = ["Method", "MethodInfo", "available_methods", "make_method", "register_method"]
