"""Offscreen rendering without a display: MuJoCo's OpenGL backend choice and its renderer.

MuJoCo picks its OpenGL backend once, from ``MUJOCO_GL``, when ``mujoco`` is first imported. On Linux
without a display the default (GLFW) cannot open a context, so :func:`prefer_headless_gl` (called on
``import handsim`` and by the ``handsim`` command, before handsim imports ``mujoco``) selects EGL (GPU, or
Mesa's software EGL) unless the user chose a backend. A process that imported ``mujoco`` first keeps the
backend it got; :func:`offscreen_renderer` then fails with a :class:`~handsim.errors.RenderError` saying
what to set. This module imports ``mujoco`` only inside its functions.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING

from handsim.errors import RenderError

if TYPE_CHECKING:
    import mujoco

HEADLESS_GL = "egl"
"""Backend selected when there is no display: EGL (GPU, or Mesa's software renderer)."""


def prefer_headless_gl() -> str | None:
    """Select MuJoCo's EGL backend on Linux without a display, unless ``MUJOCO_GL`` is already set.

    Only effective before ``mujoco`` is first imported in the process (and in processes started later,
    which inherit the environment).

    Returns:
        The backend this call selected, or None when it left ``MUJOCO_GL`` alone.
    """
    if not sys.platform.startswith("linux") or "MUJOCO_GL" in os.environ:
        return None
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None
    os.environ["MUJOCO_GL"] = HEADLESS_GL
    return HEADLESS_GL


def offscreen_renderer(model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
    """A :class:`mujoco.Renderer` of ``width`` × ``height`` pixels for ``model``.

    Raises:
        RenderError: The size exceeds the model's offscreen buffer, or no OpenGL context could be made
            (the message names MuJoCo's backend and what to set).
    """
    import mujoco

    limit = (int(model.vis.global_.offwidth), int(model.vis.global_.offheight))
    if not (0 < width <= limit[0] and 0 < height <= limit[1]):
        raise RenderError(f"image size {width} × {height} is outside 1 × 1 … {limit[0]} × {limit[1]} pixels")
    try:
        return mujoco.Renderer(model, height=height, width=width)
    except Exception as err:  # GLFW, EGL and OSMesa fail with different types (FatalError, ImportError…)
        raise RenderError(
            f"cannot create an offscreen OpenGL context with MuJoCo's {gl_backend()} backend: "
            f"{type(err).__name__}: {str(err).strip()}. Without a display, set MUJOCO_GL=egl (or osmesa) "
            "before mujoco is first imported: import handsim before mujoco, or set it in the environment"
        ) from err


def gl_backend() -> str:
    """The OpenGL backend MuJoCo chose when it was imported (``glfw``, ``egl``, ``osmesa``…)."""
    try:
        from mujoco.rendering.classic import gl_context
    except ImportError:
        return "unknown"
    module = getattr(getattr(gl_context, "GLContext", None), "__module__", "")
    return module.removeprefix("mujoco.").split(".")[0] or "no"
