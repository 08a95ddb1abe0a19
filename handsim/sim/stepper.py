"""The one stepping loop: control frames of ``substeps`` MuJoCo steps, warnings checked after each frame.

MuJoCo does not raise when a simulation goes wrong: it counts a warning and, for a bad position, velocity
or acceleration, resets the state and goes on. :class:`Stepper` checks the counters after every control
frame; a divergence warning stops the run and names the step it happened at.
"""

from __future__ import annotations

import collections
import copy
import threading
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.errors import SimulationError
from handsim.sim.scene.compiled import SimScene
from handsim.sim.warnings import WARNING_NAMES

DIVERGENCE_WARNINGS = frozenset({"mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC", "mjWARN_BADCTRL"})
"""Warnings after which the state is no longer the simulation of the inputs (MuJoCo reset it, or replaced
a NaN control by zero)."""
_RESETTING = frozenset({"mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC"})
_THREAD = threading.local()


def _messages() -> collections.deque[str]:
    """This thread's MuJoCo warning messages not yet attached to an event.

    MuJoCo calls its warning hook in the thread whose call raised the warning, so runs on threads
    (:mod:`handsim.sim.parallel`) each get their own messages, never another run's; a stepper's creation
    and reset clear them, so a message left unread by earlier work in the thread (a collision query, a
    forward pass) is not attached to its events either, on one thread or several alike.
    """
    messages = getattr(_THREAD, "messages", None)
    if messages is None:
        messages = _THREAD.messages = collections.deque(maxlen=64)
    return messages


def _record_warning(message: str) -> None:
    """MuJoCo's warning hook: only record (printing would clutter; raising inside a hook aborts)."""
    _messages().append(message.strip())


def capture_mujoco_warnings() -> None:
    """Route MuJoCo's warning messages (process-wide) into a buffer the stepper attaches to its events."""
    if mujoco.get_mju_user_warning() is not _record_warning:
        mujoco.set_mju_user_warning(_record_warning)


@dataclass(frozen=True)
class WarningEvent:
    """A MuJoCo warning raised during a control frame.

    Attributes:
        name: MuJoCo's name (``mjWARN_BADQACC`` …).
        step: Index of the MuJoCo step it happened in (0 = the first step of the run). For warnings that
            reset the state it is exact; for others it is the frame's first step.
        frame: Index of the control frame.
        count: New occurrences in the frame.
        info: MuJoCo's ``lastinfo`` (e.g. the DoF with a bad acceleration).
        diverged: The state was reset or a control replaced: the run stops here.
        message: MuJoCo's message text, when its warning hook caught one during the frame.
    """

    name: str
    step: int
    frame: int
    count: int
    info: int
    diverged: bool
    message: str = ""

    def describe(self) -> str:
        """One line for people."""
        what = "diverged" if self.diverged else "warning"
        return f"{what}: {self.name} ×{self.count} at step {self.step} (frame {self.frame}, info {self.info})"


class Stepper:
    """Steps a scene in control frames and records the sensors and the state after each frame.

    Pickles with its state (model, data, frame, warnings seen).

    Args:
        scene: The scene.
        substeps: MuJoCo steps per control frame (≥ 1).
        own_model: Step a private copy of the scene's model (for runs that switch collisions on the
            model, :class:`~handsim.sim.drive.ScheduleDriver`), leaving ``scene.model`` untouched.
    """

    def __init__(self, scene: SimScene, substeps: int, *, own_model: bool = False) -> None:
        if substeps < 1:
            raise ValueError(f"substeps must be ≥ 1, got {substeps}")
        self.scene = scene
        self.model = copy.deepcopy(scene.model) if own_model else scene.model
        self.data = mujoco.MjData(self.model)
        self.substeps = int(substeps)
        self.frame = 0
        self._counts = self.data.warning.number  # a view: updated in place by MuJoCo
        self._seen = np.zeros_like(self._counts)
        self._seen_bytes = self._seen.tobytes()  # comparing bytes is the cheapest check per frame
        capture_mujoco_warnings()
        _messages().clear()  # messages of earlier calls in this thread are not this run's

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        del state["_counts"]  # a view into data: recreated from the unpickled data
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._counts = self.data.warning.number

    def reset(self) -> None:
        """Back to the model's reference state (``qpos0``), frame 0, warnings (and their messages) cleared."""
        mujoco.mj_resetData(self.model, self.data)
        _messages().clear()
        self._counts = self.data.warning.number
        self._seen[:] = 0
        self._seen_bytes = self._seen.tobytes()
        self.frame = 0

    def step(self, ctrl: npt.ArrayLike | None = None) -> tuple[WarningEvent, ...]:
        """Advance one control frame with ``ctrl`` held (zero-order hold).

        Args:
            ctrl: Actuator controls (nu,), or None to keep the current ones.

        Returns:
            The warnings of the frame (empty almost always); a run must stop after one that ``diverged``.
        """
        if ctrl is not None:
            self.data.ctrl[:] = ctrl
        mujoco.mj_step(self.model, self.data, nstep=self.substeps)
        self.frame += 1
        if self._counts.tobytes() == self._seen_bytes:
            return ()
        return self._new_warnings()

    def _new_warnings(self) -> tuple[WarningEvent, ...]:
        messages = _messages()
        message = " | ".join(messages)
        messages.clear()
        events = warning_events(
            self._counts,
            self._seen,
            self.data.warning.lastinfo,
            frame=self.frame - 1,
            substeps=self.substeps,
            steps_since_reset=round(self.data.time / self.model.opt.timestep),
            message=message,
        )
        self._seen[:] = self._counts
        self._seen_bytes = self._seen.tobytes()
        return events


def warning_events(
    counts: np.ndarray,
    seen: np.ndarray,
    lastinfo: np.ndarray,
    *,
    frame: int,
    substeps: int,
    steps_since_reset: int,
    message: str = "",
) -> tuple[WarningEvent, ...]:
    """The warnings MuJoCo counted during control frame ``frame`` (one simulation).

    Args:
        counts: MuJoCo's warning counters after the frame (``data.warning.number``).
        seen: The counters before it.
        lastinfo: MuJoCo's ``lastinfo`` per warning.
        frame: Index of the control frame.
        substeps: MuJoCo steps per control frame.
        steps_since_reset: ``round(data.time / timestep)`` after the frame: a reset sets time to 0, so for
            warnings that reset the state the steps after it (the reset's own included) say where it was.
        message: MuJoCo's message text caught during the frame.
    """
    events = []
    first = frame * substeps
    for i in np.flatnonzero(counts != seen):
        name = WARNING_NAMES[i]
        step = first + substeps - steps_since_reset if name in _RESETTING else first
        events.append(
            WarningEvent(
                name=name,
                step=step,
                frame=frame,
                count=int(counts[i] - seen[i]),
                info=int(lastinfo[i]),
                diverged=name in DIVERGENCE_WARNINGS,
                message=message,
            )
        )
    return tuple(events)


def check_controls(values: np.ndarray, what: str) -> None:
    """Raise if controls hold NaN or Inf (MuJoCo would silently replace them by zero).

    Raises:
        SimulationError: Naming the first bad frame and column.
    """
    bad = ~np.isfinite(values)
    if bad.any():
        frame, column = (int(x[0]) for x in np.nonzero(bad))
        raise SimulationError(f"{what}: non-finite value at frame {frame}, column {column}")
