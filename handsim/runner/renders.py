"""A few rendered frames per trial (headless), as PNG bytes for ``OUT/frames/<safe-id>/<frame>.png``.

Which frames (:func:`key_frames`), in this order of choice: the frame with the most hand links touching
the object, the grasp (glove trials: the start of the hold window; recorded trials: the first frame with
hand–object contact), the first and the last; more frames, when asked, evenly between.

Each frame is seen from the ``frame`` camera (:func:`handsim.viz.render.frame_camera`): aimed at that
moment's objects and hands together, so a two-hand ARCTIC frame shows both hands and the object, and a glove
frame the hand with its object wherever it fell. Rendering needs an OpenGL context (without a display EGL,
unless ``MUJOCO_GL`` says otherwise: :mod:`handsim.viz.headless`); when there is none the trial gets a note
and no frames, not an error.
"""

from __future__ import annotations

import hashlib
import re

import numpy as np

from handsim.errors import HandsimError
from handsim.runner.png import encode_png
from handsim.runner.trial_record import touching_links
from handsim.sim.replay import ReplayResult
from handsim.sim.scene.compiled import SimScene
from handsim.viz.headless import offscreen_backend
from handsim.viz.render import FRAME_CAMERA, render_states

FRAMES_DIR = "frames"
RENDER_CAMERA = FRAME_CAMERA
RENDER_SIZE = (320, 240)
"""Width and height of a rendered frame, pixels (small: the report embeds them)."""
RENDER_SHADOWS = False
"""Shadows make software OpenGL (Mesa's EGL without a GPU) 3–4× slower; frames are for a quick look."""
RENDER_MULTISAMPLE = False
"""Anti-aliasing (the model's 4× multisampling) makes software OpenGL about 1.7× slower (4 frames of a
GraspDB14 trial: 0.41 → 0.25 s with the renderer made); at 320 × 240 for a quick look, edges may be
jagged."""


def safe_id(trial_id: str) -> str:
    """A folder name for a trial id: unsafe characters replaced, plus a hash that keeps it unique.

    ``Models/20`` → ``Models_20-<8 hex digits of the id's SHA-256>``.
    """
    readable = re.sub(r"[^A-Za-z0-9._-]+", "_", trial_id).strip("._") or "trial"
    return f"{readable[:80]}-{hashlib.sha256(trial_id.encode('utf-8')).hexdigest()[:8]}"


def key_frames(result: ReplayResult, count: int) -> list[int]:
    """The frames to render, sorted; chosen in this order: most contact, grasp, first, last, then evenly.

    Args:
        result: A replay result.
        count: How many frames (at most the frames simulated).

    Returns:
        Distinct frame indices into the simulated frames, ascending.
    """
    n = int(result.frames.times.shape[0])
    if count <= 0 or n == 0:
        return []
    touching = touching_links(result).sum(axis=1)
    if result.hold is not None:
        grasp = int(np.searchsorted(result.frames.times, result.hold.window[0] - 1e-9))
    else:
        grasp = int(np.argmax(touching > 0)) if touching.any() else 0
    wanted = [int(np.argmax(touching)), min(grasp, n - 1), 0, n - 1]  # most telling first
    wanted += np.round(np.linspace(0, n - 1, max(count, 2))).astype(int).tolist()
    chosen: list[int] = []
    for frame in wanted:
        if frame not in chosen:
            chosen.append(frame)
        if len(chosen) == count:
            break
    return sorted(chosen)


def headless_glfw() -> bool:
    """True when ``MUJOCO_GL=glfw`` was chosen on Linux without a display: no offscreen context can be made.

    Trying GLFW without a display can abort the process, so it is not tried; with ``MUJOCO_GL`` unset the
    renderer takes EGL itself (:func:`handsim.viz.headless.offscreen_backend`).
    """
    return offscreen_backend() is None


def render_pngs(scene: SimScene, result: ReplayResult, frames: list[int]) -> list[bytes]:
    """Render frames of a replay (``result.states`` needed) as PNG files' bytes.

    Raises:
        HandsimError: No OpenGL context (or any error of :func:`handsim.viz.render.render_states`).
        ValueError: The result kept no states.
    """
    if headless_glfw():
        raise HandsimError(
            "MuJoCo was imported with its GLFW OpenGL backend (MUJOCO_GL=glfw) and there is no display; "
            "unset MUJOCO_GL, or set it to egl or osmesa"
        )
    if result.states is None:
        raise ValueError("the replay kept no states; replay with ReplayConfig(keep_states=True)")
    width, height = RENDER_SIZE
    images = render_states(
        scene,
        result.states[frames],
        camera=RENDER_CAMERA,
        width=width,
        height=height,
        shadows=RENDER_SHADOWS,
        multisample=RENDER_MULTISAMPLE,
    )
    return [encode_png(image) for image in images]
