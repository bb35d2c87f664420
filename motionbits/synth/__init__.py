"""Generators of benchmark clips with exact ground truth.

``planar`` needs only numpy and OpenCV; MuJoCo scenes need the ``[sim]`` extra.
"""

from motionbits.synth.planar import Body, PlanarClip, Polygon, demo_clip, render_planar_clip

__all__ = ["Body", "PlanarClip", "Polygon", "demo_clip", "render_planar_clip"]
