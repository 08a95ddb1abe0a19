"""Pictures of a replay: its states rendered offscreen with :class:`mujoco.Renderer`, written as a video.

A replay keeps the state of every control frame when asked (``ReplayConfig(keep_states=True)``);
:func:`render_states` puts each state into an ``MjData``, runs ``mj_forward`` and renders it from a camera
of the scene (``hand_cam``, ``overview``), from a camera tracking the (first) hand (``track``), or from one
that frames every object and every hand (``frame``: aimed at each state's box around them, from just far
enough for it to fit the view; a two-hand ARCTIC scene's frames show both hands and the object, where
``track`` follows one hand and may leave the rest out).
:func:`write_video` renders every ``stride``-th state, so that the video plays in real time at about
:data:`DEFAULT_FPS`, and encodes it:

* ``.mp4`` — H.264 (libx264; MPEG-4 part 2 where the FFmpeg build lacks it) through PyAV, the optional
  ``video`` extra: ``pip install "handsim[video]"``;
* ``.gif`` — an animated GIF through Pillow (a dependency of matplotlib, the ``plot`` extra).

Rendering needs an OpenGL context, chosen when the renderer is made (:mod:`handsim.viz.headless`): on Linux
without a display, EGL (GPU, or Mesa's software EGL) unless ``MUJOCO_GL`` is set; set ``MUJOCO_GL``
(e.g. ``osmesa``) in the environment to choose another.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.errors import HandsimError
from handsim.sim.scene.compiled import SimScene
from handsim.viz.headless import offscreen_renderer

DEFAULT_FPS = 30.0
"""Target frame rate of a video, Hz; the exact rate is the control rate over a whole stride."""
TRACK_CAMERA = "track"
"""Camera name that follows the hand's root body (a tracking free camera) instead of a fixed camera."""
FRAME_CAMERA = "frame"
"""Camera name that frames the scene's objects and hands: a free camera aimed at the box around them."""
VIDEO_FORMATS = {
    ".mp4": 'H.264 video (PyAV: pip install "handsim[video]")',
    ".gif": "animated GIF (Pillow)",
}
_QUALITY_LOCK = threading.Lock()  # a model's offsamples and shadowsize are 0 only while a renderer is made
_TRACK_DISTANCE = 0.45  # m
_TRACK_AZIMUTH = 135.0  # degrees
_TRACK_ELEVATION = -25.0  # degrees
_FRAME_MARGIN = 0.9
"""The framed box fills at most this fraction of the view's half-height and half-width: room around it."""
_FRAME_MIN_DISTANCE = 0.2  # m: no closer, however small the box (a lone fingertip)


@dataclass(frozen=True)
class Video:
    """A video written by :func:`write_video`.

    Attributes:
        path: The file.
        frames: Images in it.
        fps: Its frame rate, Hz (real time: ``1 / (stride · frame_dt)``).
        stride: Replay frames per image.
        width: Image width, pixels.
        height: Image height, pixels.
        camera: The camera it was rendered from.
        codec: The encoder (``libx264``, ``mpeg4``, ``gif``).
    """

    path: Path
    frames: int
    fps: float
    stride: int
    width: int
    height: int
    camera: str
    codec: str


def frame_stride(frame_dt: float, fps: float = DEFAULT_FPS) -> int:
    """Replay frames per video image so that the video plays in real time at about ``fps``.

    Args:
        frame_dt: Seconds per replay frame.
        fps: Wanted video frame rate, Hz.

    Returns:
        The stride, at least 1.
    """
    if not (frame_dt > 0 and fps > 0):
        raise ValueError(f"frame_dt and fps must be positive, got {frame_dt} and {fps}")
    return max(1, round(1.0 / (fps * frame_dt)))


def camera_names(scene: SimScene) -> tuple[str, ...]:
    """Cameras :func:`render_states` accepts: the scene's, :data:`TRACK_CAMERA` and :data:`FRAME_CAMERA`."""
    model = scene.model
    return (*(model.camera(i).name for i in range(model.ncam)), TRACK_CAMERA, FRAME_CAMERA)


def _framed_geoms(scene: SimScene) -> np.ndarray:
    """The geoms :data:`FRAME_CAMERA` frames: every hand's and every object's (not the floor, the stand)."""
    model = scene.model
    layout = scene.layout
    roots = {layout.root_body, *(h.root_body for h in layout.hands), *(o.root_body for o in layout.objects)}
    movers = sorted({int(model.body_rootid[b]) for b in roots if b > 0} - {0})  # never the world's own
    return np.flatnonzero(np.isin(model.body_rootid[model.geom_bodyid], movers))


def framed_box(scene: SimScene, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
    """The box around every object and every hand of the scene in ``data``'s state: lower, upper corner (m).

    Each geom of a hand's or an object's bodies counts as its own bounding box (MuJoCo's ``geom_aabb``) as
    placed in ``data`` (after ``mj_kinematics`` or ``mj_forward``); the static world does not count. A scene
    with none of them: the hand's root, a point.

    Returns:
        The corners (3,) and (3,).
    """
    geoms = _framed_geoms(scene)
    if not geoms.size:
        point = data.xpos[scene.layout.root_body].copy()
        return point, point
    aabb = scene.model.geom_aabb[geoms]  # centre (3) and half sizes (3) in the geom's frame
    turns = data.geom_xmat[geoms].reshape(-1, 3, 3)
    centres = data.geom_xpos[geoms] + np.einsum("gij,gj->gi", turns, aabb[:, :3])
    halves = np.einsum("gij,gj->gi", np.abs(turns), aabb[:, 3:])
    return (centres - halves).min(axis=0), (centres + halves).max(axis=0)


def frame_camera(scene: SimScene, data: mujoco.MjData, aspect: float) -> mujoco.MjvCamera:
    """The :data:`FRAME_CAMERA` for ``data``'s state: a free camera aimed at :func:`framed_box`.

    It looks from the track camera's direction (azimuth 135°, elevation −25°) at the box's centre, from the
    nearest distance at which every corner of the box is inside the view, vertically (``fovy``) and
    horizontally (``fovy`` widened by ``aspect``), with :data:`_FRAME_MARGIN` to spare.

    Args:
        scene: The scene.
        data: Its state, after ``mj_kinematics`` or ``mj_forward``.
        aspect: Image width / height.

    Returns:
        The camera.
    """
    low, high = framed_box(scene, data)
    centre = (low + high) / 2.0
    az, el = np.radians(_TRACK_AZIMUTH), np.radians(_TRACK_ELEVATION)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    corners = np.array(
        [[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])]
    )
    offsets = corners - centre
    tan_v = _FRAME_MARGIN * np.tan(np.radians(scene.model.vis.global_.fovy) / 2.0)
    tan_h = tan_v * aspect
    # a corner at depth d + o·forward is in view when |o·up| ≤ depth · tan_v and |o·right| ≤ depth · tan_h
    needed = np.maximum(np.abs(offsets @ up) / tan_v, np.abs(offsets @ right) / tan_h) - offsets @ forward
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = centre
    cam.distance = max(_FRAME_MIN_DISTANCE, float(needed.max()))
    cam.azimuth = _TRACK_AZIMUTH
    cam.elevation = _TRACK_ELEVATION
    return cam


def _camera(scene: SimScene, camera: str) -> str | mujoco.MjvCamera | None:
    """The camera to render from; None for :data:`FRAME_CAMERA`, aimed anew at each state."""
    if camera == FRAME_CAMERA:
        return None
    if camera == TRACK_CAMERA:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        cam.trackbodyid = scene.layout.root_body
        cam.distance = _TRACK_DISTANCE
        cam.azimuth = _TRACK_AZIMUTH
        cam.elevation = _TRACK_ELEVATION
        return cam
    if mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
        raise HandsimError(f"unknown camera {camera!r}; the scene has {list(camera_names(scene))}")
    return camera


def _renderer(scene: SimScene, width: int, height: int, multisample: bool, shadows: bool) -> mujoco.Renderer:
    """The offscreen renderer: without ``multisample`` no multisampled buffer, without ``shadows`` no shadows.

    MuJoCo reads ``vis.quality.offsamples`` and ``vis.quality.shadowsize`` when it makes the context: they
    are 0 for that moment only. A context without the model's 4096² shadow map is made in 16 ms instead of
    50–60 ms with Mesa's software EGL (the mug scene), and renders the same pixels when no shadow is cast.
    """
    quality = scene.model.vis.quality
    with _QUALITY_LOCK:  # read under the lock too: another thread's renderer may have them at 0 just now
        kept = {name: int(getattr(quality, name)) for name in ("offsamples", "shadowsize")}
        wanted = {
            "offsamples": kept["offsamples"] if multisample else 0,
            "shadowsize": kept["shadowsize"] if shadows else 0,
        }
        if wanted == kept:
            return offscreen_renderer(scene.model, width, height)
        try:
            for name, value in wanted.items():
                setattr(quality, name, value)
            return offscreen_renderer(scene.model, width, height)
        finally:
            for name, value in kept.items():
                setattr(quality, name, value)


def render_states(
    scene: SimScene,
    states: npt.ArrayLike,
    *,
    camera: str = "hand_cam",
    width: int = 640,
    height: int = 480,
    stride: int = 1,
    shadows: bool = True,
    multisample: bool = True,
) -> Iterator[np.ndarray]:
    """Render replay states, one image per ``stride``-th state.

    Args:
        scene: The replayed scene.
        states: ``qpos`` per frame (N, nq), e.g. ``ReplayResult.states``.
        camera: A camera of the scene (``hand_cam``, ``overview``), :data:`TRACK_CAMERA` or
            :data:`FRAME_CAMERA` (aimed at each state's objects and hands: :func:`frame_camera`).
        width: Image width, pixels (at most the scene's offscreen buffer, 1280).
        height: Image height, pixels (at most 960).
        stride: Render states 0, stride, 2 · stride …
        shadows: Cast shadows (3–4× slower with software OpenGL).
        multisample: Anti-alias edges with the model's multisampling (``vis.quality.offsamples``); off,
            software OpenGL renders about 1.7× as fast, with jagged edges.

    Yields:
        RGB images (height, width, 3), uint8.

    Raises:
        HandsimError: Unknown camera, bad image size, states of another model, or no OpenGL context.
    """
    qpos = np.asarray(states, dtype=float)
    model = scene.model
    if qpos.ndim != 2 or qpos.shape[1] != model.nq:
        raise HandsimError(f"states must be (frames, {model.nq}) qpos rows of this scene, got {qpos.shape}")
    if stride < 1:
        raise ValueError(f"stride must be ≥ 1, got {stride}")
    cam = _camera(scene, camera)
    data = mujoco.MjData(model)
    renderer = _renderer(scene, width, height, multisample, shadows)
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = shadows
    try:
        for q in qpos[::stride]:
            data.qpos[:] = q
            mujoco.mj_forward(model, data)
            view = frame_camera(scene, data, width / height) if cam is None else cam
            renderer.update_scene(data, camera=view)
            yield renderer.render()
    finally:
        renderer.close()


def write_video(
    scene: SimScene,
    states: npt.ArrayLike,
    frame_dt: float,
    path: str | Path,
    *,
    fps: float = DEFAULT_FPS,
    camera: str = "hand_cam",
    width: int = 640,
    height: int = 480,
    shadows: bool = True,
) -> Video:
    """Render replay states and write them as a real-time video.

    Args:
        scene: The replayed scene.
        states: ``qpos`` per frame (N, nq): ``ReplayResult.states`` of a replay with ``keep_states=True``.
        frame_dt: Seconds per replay frame (``ReplayResult.frame_dt``).
        path: ``.mp4`` or ``.gif`` file to write (its folder is created); it appears whole or not at all
            (written under a temporary name, then renamed).
        fps: Wanted frame rate, Hz (the written rate is ``1 / (stride · frame_dt)``).
        camera: See :func:`render_states`.
        width: Image width, pixels (even, for H.264).
        height: Image height, pixels (even, for H.264).
        shadows: Cast shadows.

    Returns:
        What was written.

    Raises:
        HandsimError: Unknown format, missing encoder (the message names the extra to install), or a
            rendering problem (see :func:`render_states`).
    """
    out = Path(path)
    encode = _encoder(out, width, height)
    stride = frame_stride(frame_dt, fps)
    rate = Fraction(1.0 / (stride * frame_dt)).limit_denominator(1000)
    images = render_states(
        scene, states, camera=camera, width=width, height=height, stride=stride, shadows=shadows
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_name(f".{out.stem}.partial{os.getpid()}{out.suffix}")  # the suffix picks the format
    try:
        count, codec = encode(partial, images, rate)
        os.replace(partial, out)
    except BaseException:  # a render error, a full disk, Ctrl-C: no half-written video left behind
        with contextlib.suppress(OSError):
            partial.unlink(missing_ok=True)
        raise
    return Video(out, count, float(rate), stride, width, height, camera, codec)


def check_video(path: str | Path, width: int = 640, height: int = 480) -> None:
    """Check that :func:`write_video` can write ``path`` at this size, before spending time on a replay.

    Raises:
        HandsimError: Unknown format, odd size for H.264, or the encoder is not installed (the message
            names the extra to install).
    """
    _encoder(Path(path), width, height)


def _encoder(out: Path, width: int, height: int):
    suffix = out.suffix.lower()
    if suffix not in VIDEO_FORMATS:
        listing = ", ".join(f"{k} ({v})" for k, v in VIDEO_FORMATS.items())
        raise HandsimError(f"{out}: unknown video format {out.suffix!r}; handsim writes {listing}")
    if suffix == ".mp4" and (width % 2 or height % 2):
        raise HandsimError(f"H.264 needs an even image size, got {width} × {height}")
    return _mp4_writer() if suffix == ".mp4" else _gif_writer()


def _mp4_writer():
    try:
        import av  # lazy: optional extra handsim[video]
    except ImportError as exc:
        raise HandsimError('.mp4 videos need PyAV: pip install "handsim[video]" (or write a .gif)') from exc

    def encode(path: Path, images: Iterator[np.ndarray], rate: Fraction) -> tuple[int, str]:
        codec = "libx264" if "libx264" in av.codecs_available else "mpeg4"
        count = 0
        with av.open(str(path), mode="w") as container:
            stream = container.add_stream(codec, rate=rate)
            stream.pix_fmt = "yuv420p"
            for image in images:
                if count == 0:
                    stream.height, stream.width = image.shape[:2]
                frame = av.VideoFrame.from_ndarray(image, format="rgb24")
                container.mux(stream.encode(frame))
                count += 1
            container.mux(stream.encode())
        return count, codec

    return encode


def _gif_writer():
    try:
        from PIL import Image  # lazy: Pillow, matplotlib's dependency (handsim[plot]), for GIFs only
    except ImportError as exc:
        raise HandsimError('.gif videos need Pillow: pip install "handsim[plot]" (or pillow)') from exc

    def encode(path: Path, images: Iterator[np.ndarray], rate: Fraction) -> tuple[int, str]:
        frames = [Image.fromarray(image) for image in images]
        if not frames:
            raise HandsimError("no states to render")
        duration = round(1000.0 / float(rate))  # ms per image (GIF stores 10 ms steps)
        frames[0].save(path, save_all=True, append_images=frames[1:], duration=duration, loop=0)
        return len(frames), "gif"

    return encode
