"""Offscreen rendering without a display: the OpenGL backend, chosen when a renderer is made.

MuJoCo picks its OpenGL backend once, from ``MUJOCO_GL``, when ``mujoco`` is first imported; unset, that
is GLFW, which needs a display (and can abort the process without one). ``import handsim`` changes no
environment variable; instead :func:`offscreen_renderer` chooses, each time it makes a renderer:

* A display (``DISPLAY`` or ``WAYLAND_DISPLAY``), not Linux, or a headless backend chosen when ``mujoco``
  was imported: MuJoCo's choice.
* Otherwise (MuJoCo took GLFW on Linux without a display): the backend ``MUJOCO_GL`` names now, ``egl``
  or ``osmesa`` (set after ``mujoco`` was imported), or EGL (GPU, or Mesa's software EGL) when it is
  unset, for this renderer only: MuJoCo's own default for other code in the process is left as it is.
  ``MUJOCO_GL=glfw`` is refused with a :class:`~handsim.errors.RenderError`, not tried.

To override, set ``MUJOCO_GL`` (``egl``, ``osmesa``, ``glfw``…) in the environment before the process
starts (``MUJOCO_GL=osmesa`` where EGL is missing). Importing MuJoCo's EGL or OSMesa module sets
``PYOPENGL_PLATFORM`` when it is unset (MuJoCo does that, on the first headless renderer; handsim sets
nothing on import). This module imports ``mujoco`` only inside its functions.
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

from handsim.errors import RenderError

if TYPE_CHECKING:
    import mujoco

HEADLESS_GL = "egl"
"""Backend used on Linux without a display when ``MUJOCO_GL`` is unset: EGL (GPU, or Mesa's software
renderer). No fallback to OSMesa in the same process: MuJoCo's EGL module has then set
``PYOPENGL_PLATFORM=egl``, which its OSMesa module refuses."""
HEADLESS_BACKENDS = ("egl", "osmesa")
"""The backends a renderer can use without a display; ``MUJOCO_GL`` may name one after ``mujoco``'s import."""

_SWAP_LOCK = threading.Lock()  # one renderer at a time is made with a substituted GL context class


def has_display() -> bool:
    """Whether a display server is named in the environment (``DISPLAY`` or ``WAYLAND_DISPLAY``)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def gl_backend() -> str:
    """The OpenGL backend MuJoCo chose when it was imported (``glfw``, ``egl``, ``osmesa``…)."""
    try:  # lazy: this module is imported where MuJoCo is not needed yet (so are the imports below)
        from mujoco.rendering.classic import gl_context
    except ImportError:
        return "unknown"
    module = getattr(getattr(gl_context, "GLContext", None), "__module__", "")
    return module.removeprefix("mujoco.").split(".")[0] or "no"


def offscreen_backend() -> str | None:
    """The backend :func:`offscreen_renderer` will use; None when none can work.

    None only for GLFW on Linux without a display chosen by the user (``MUJOCO_GL=glfw``, or another
    value naming no headless backend): that backend is not tried, because it can abort the process.
    """
    mujoco_choice = gl_backend()
    if not sys.platform.startswith("linux") or has_display() or mujoco_choice != "glfw":
        return mujoco_choice
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    if not requested:
        return HEADLESS_GL
    return requested if requested in HEADLESS_BACKENDS else None


def offscreen_renderer(model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
    """A :class:`mujoco.Renderer` of ``width`` × ``height`` pixels for ``model`` on :func:`offscreen_backend`.

    Raises:
        RenderError: The size exceeds the model's offscreen buffer, or no OpenGL context could be made
            (the message names the backend, its error and what to set).
    """
    import mujoco  # lazy: see gl_backend

    limit = (int(model.vis.global_.offwidth), int(model.vis.global_.offheight))
    if not (0 < width <= limit[0] and 0 < height <= limit[1]):
        raise RenderError(f"image size {width} × {height} is outside 1 × 1 … {limit[0]} × {limit[1]} pixels")
    backend = offscreen_backend()
    if backend is None:
        raise RenderError(
            "cannot create an offscreen OpenGL context: MUJOCO_GL selects MuJoCo's GLFW backend and there is "
            "no display (DISPLAY, WAYLAND_DISPLAY); unset MUJOCO_GL, or set it to egl or osmesa"
        )
    try:
        if backend == gl_backend():
            return mujoco.Renderer(model, height=height, width=width)
        return _renderer_with(_context_class(backend), model, width, height)
    except Exception as err:  # GLFW, EGL and OSMesa fail with different types (FatalError, ImportError…)
        raise RenderError(
            f"cannot create an offscreen OpenGL context with the {backend} backend: "
            f"{type(err).__name__}: {str(err).strip()}. Set MUJOCO_GL to a backend that works here (egl, "
            "osmesa, or glfw with a display) in the environment before starting Python"
        ) from err


def _context_class(backend: str) -> Callable[[int, int], object]:
    """MuJoCo's OpenGL context class of ``backend`` (in :data:`HEADLESS_BACKENDS`), imported when used."""
    if backend == "egl":
        from mujoco.egl import GLContext  # lazy: needs libEGL and sets PYOPENGL_PLATFORM; only when used
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext  # lazy: needs libOSMesa and sets PYOPENGL_PLATFORM
    else:
        raise ValueError(f"no headless context class for backend {backend!r}")
    return GLContext


def _renderer_with(
    context: Callable[[int, int], object], model: mujoco.MjModel, width: int, height: int
) -> mujoco.Renderer:
    """A :class:`mujoco.Renderer` whose OpenGL context is of class ``context``.

    ``mujoco.Renderer`` makes its context from ``mujoco.rendering.classic.gl_context.GLContext``, the
    class MuJoCo chose on import, and keeps the instance; that name is bound to ``context`` only while
    this renderer is made (under a lock), then restored.
    """
    # lazy: see gl_backend
    import mujoco
    from mujoco.rendering.classic import gl_context

    with _SWAP_LOCK:
        chosen = gl_context.GLContext
        gl_context.GLContext = context
        try:
            return mujoco.Renderer(model, height=height, width=width)
        finally:
            gl_context.GLContext = chosen


def prefer_headless_gl() -> str | None:
    """Set ``MUJOCO_GL=egl`` in this process's environment on Linux without a display, unless it is set.

    Not needed by handsim's own renderers (:func:`offscreen_renderer` chooses when it renders) and never
    called on import; it only affects ``mujoco`` imported after the call, here or in child processes.

    Returns:
        The backend this call selected, or None when it left ``MUJOCO_GL`` alone.
    """
    choice = headless_gl_default()
    if choice is not None:
        os.environ["MUJOCO_GL"] = choice
    return choice


def headless_gl_default() -> str | None:
    """The backend :func:`prefer_headless_gl` would set, without setting it.

    For another process's environment (a Ray worker's), leaving this process's own alone.

    Returns:
        ``HEADLESS_GL`` on Linux without a display and without ``MUJOCO_GL``; else None.
    """
    if not sys.platform.startswith("linux") or "MUJOCO_GL" in os.environ or has_display():
        return None
    return HEADLESS_GL
