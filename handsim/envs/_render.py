"""Headless rendering for the environments: MuJoCo's offscreen renderer, never a window.

MuJoCo picks its OpenGL backend once, from ``MUJOCO_GL``, when ``mujoco`` is first imported. On Linux
without a display the default (GLFW) cannot open a context, so :func:`prefer_headless_gl` (called when
:mod:`handsim.envs` is imported, i.e. on ``import handsim``, before handsim imports ``mujoco``) selects
EGL unless the user chose a backend. A process that imported ``mujoco`` before ``handsim`` keeps the
backend it got; :class:`OffscreenRenderer` then fails with a :class:`RenderError` saying what to set.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING

from handsim.errors import HandsimError

if TYPE_CHECKING:  # mujoco is imported lazily: MUJOCO_GL must be set before its first import
    import mujoco
    import numpy as np

HEADLESS_GL = "egl"
"""Backend selected when there is no display: EGL (GPU, or Mesa's software renderer)."""


class RenderError(HandsimError):
    """No offscreen OpenGL context could be created (no display and no EGL/OSMesa backend)."""


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
    os.environ.setdefault("MUJOCO_GL", HEADLESS_GL)
    return HEADLESS_GL


def camera_id(model: mujoco.MjModel, camera: str | None) -> int:
    """Id of a named camera of ``model``; None is MuJoCo's free camera (-1).

    Raises:
        ValueError: No camera of that name; the message lists the model's cameras.
    """
    import mujoco

    if camera is None:
        return -1
    cam = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera))
    if cam < 0:
        names = [model.camera(i).name for i in range(model.ncam)]
        raise ValueError(f"unknown camera {camera!r}; the scene's cameras are {names} (or None: free camera)")
    return cam


class OffscreenRenderer:
    """RGB frames of a scene from one camera through :class:`mujoco.Renderer`, created on first use.

    Picklable: the GL context is not pickled; a copy creates its own on its first frame.

    Args:
        model: The model (only checked here: the offscreen buffer must hold ``width`` × ``height``).
        width: Image width, pixels.
        height: Image height, pixels.
        camera: A camera name of the model, or None for the free camera.

    Raises:
        ValueError: Non-positive size, a size larger than the model's offscreen buffer, or an unknown camera.
    """

    def __init__(self, model: mujoco.MjModel, width: int, height: int, camera: str | None) -> None:
        width, height = int(width), int(height)
        if width < 1 or height < 1:
            raise ValueError(f"width and height must be ≥ 1 pixel, got {width} × {height}")
        buffer = (int(model.vis.global_.offwidth), int(model.vis.global_.offheight))
        if width > buffer[0] or height > buffer[1]:
            raise ValueError(
                f"image {width} × {height} is larger than the scene's offscreen buffer "
                f"{buffer[0]} × {buffer[1]} (visual/global offwidth, offheight)"
            )
        self.width, self.height = width, height
        self.camera = camera
        self._camera_id = camera_id(model, camera)
        self._renderer: mujoco.Renderer | None = None

    def render(self, model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
        """The current frame, (height, width, 3) uint8.

        Raises:
            RenderError: No OpenGL context could be created.
        """
        if self._renderer is None:
            self._renderer = _make_renderer(model, self.width, self.height)
        self._renderer.update_scene(data, camera=self._camera_id)
        return self._renderer.render()

    def close(self) -> None:
        """Free the GL context (idempotent)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state


def _make_renderer(model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
    import mujoco

    try:
        return mujoco.Renderer(model, height=height, width=width)
    except Exception as err:  # GLFW, EGL and OSMesa fail with different types (FatalError, ImportError…)
        raise RenderError(
            f"cannot create an offscreen OpenGL context with MuJoCo's {_backend()} backend: "
            f"{type(err).__name__}: {err}. Without a display, set MUJOCO_GL=egl (or osmesa) before mujoco is "
            "first imported: import handsim before mujoco, or set it in the environment"
        ) from err


def _backend() -> str:
    """The OpenGL backend MuJoCo chose when it was imported (``glfw``, ``egl``, ``osmesa``…)."""
    try:
        from mujoco.rendering.classic import gl_context
    except ImportError:
        return "unknown"
    module = getattr(getattr(gl_context, "GLContext", None), "__module__", "")
    return module.removeprefix("mujoco.").split(".")[0] or "no"
