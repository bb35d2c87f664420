"""Lazy import of MuJoCo and an offscreen renderer (EGL by default, OSMesa as a fallback).

MuJoCo is an optional dependency: ``pip install motionbits[sim]``. ``MUJOCO_GL`` is set to
``egl`` unless the user chose a backend already; it must be set before mujoco is imported.
"""

from __future__ import annotations

import os
from types import ModuleType

__all__ = ["import_mujoco", "render_check"]

_INSTALL_HINT = (
    "the MuJoCo benchmark generator needs the 'mujoco' package: pip install motionbits[sim] "
    "(or pip install mujoco)"
)


def import_mujoco() -> ModuleType:
    """Import and return the ``mujoco`` module, or raise ImportError saying how to install it."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    try:
        import mujoco  # noqa: PLC0415
    except ImportError as exc:
        raise ImportError(_INSTALL_HINT) from exc
    return mujoco


def render_check() -> str | None:
    """Try a tiny offscreen render; return None if it works, else the reason it does not."""
    try:
        mujoco = import_mujoco()
    except ImportError as exc:
        return str(exc)
    try:
        model = mujoco.MjModel.from_xml_string(
            "<mujoco><worldbody><geom type='sphere' size='.1'/></worldbody></mujoco>"
        )
        data = mujoco.MjData(model)
        with mujoco.Renderer(model, 16, 16) as renderer:
            mujoco.mj_forward(model, data)
            renderer.update_scene(data)
            renderer.render()
    except Exception as exc:  # EGL/OSMesa missing, no display, driver errors ...
        gl = os.environ.get("MUJOCO_GL")
        return (f"MuJoCo cannot render offscreen with MUJOCO_GL={gl}: {exc} "
                "(EGL needs libEGL; or install Debian libosmesa6 and set MUJOCO_GL=osmesa)")
    return None
