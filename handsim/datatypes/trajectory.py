"""Recorded hand motion as joint targets: the :class:`Trajectory` data type."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from handsim.datatypes.flags import Flag
from handsim.errors import TrajectoryError


@dataclass(frozen=True)
class Phase:
    """A named interval of a trajectory, e.g. the ``grasp`` phase of a GraspDB14 trial.

    Attributes:
        name: Phase name as annotated (``rest``, ``reach``, ``grasp``, ``retract`` …).
        start: First frame of the phase.
        stop: One past the last frame (Python slice convention).
    """

    name: str
    start: int
    stop: int


@dataclass(frozen=True)
class ObjectTrack:
    """A recorded object's pose over the frames of a trajectory.

    Attributes:
        pose: Object frame pose per sample, shape (T, 7): position (m) and quaternion (w, x, y, z).
        articulation: Articulation angle per sample in radians (hinge of a two-part object), shape (T,),
            or None for a rigid object.
        valid: True where the pose was recorded and usable, shape (T,).
    """

    pose: np.ndarray
    articulation: np.ndarray | None = None
    valid: np.ndarray | None = None


@dataclass(frozen=True)
class Trajectory:
    """Joint-angle targets over time for a hand model, in SI units.

    Attributes:
        times: Sample times in seconds from the first sample, shape (T,), strictly increasing.
        dof_names: Column names; each equals the MuJoCo joint name of the DoF it drives.
        targets: Joint angles in radians, shape (T, ndof).
        valid: True where a target was measured and usable, shape (T, ndof).
        switch: Glove switch state per sample (CyberGlove recordings), shape (T,), or None.
        root_pose: Optional root pose per sample, shape (T, 7): position (m) and quaternion (w, x, y, z).
        hand_roots: Several hands (two-hand recordings such as ARCTIC's): each hand's root pose per sample,
            hand name → shape (T, 7), the hand's DoF columns named ``<hand>/<dof>``; empty for one hand
            (then ``root_pose`` holds its root).
        channels: Recorded channels that drive no DoF (kept, not dropped), name → shape (T,) array.
        computed: Names of DoFs whose values were computed rather than measured (e.g. coupled DIPs).
        filled: True where a target was filled in by gap filling, shape (T, ndof), or None.
        phases: Named frame intervals (trial phases), in time order.
        objects: Recorded object pose tracks by object name.
        source: The file the trajectory was read from.
        sha256: SHA-256 of that file's bytes ("" when not read from a file).
        notes: Decisions and repairs made while reading, for the user to see.
        flags: What a check of the recording found that makes a replay of it mean less (e.g. ARCTIC hands
            that look swapped): every replay reports them among its flags (:mod:`handsim.datatypes.flags`).
    """

    times: np.ndarray
    dof_names: tuple[str, ...]
    targets: np.ndarray
    valid: np.ndarray
    switch: np.ndarray | None = None
    root_pose: np.ndarray | None = None
    channels: dict[str, np.ndarray] = field(default_factory=dict)
    computed: tuple[str, ...] = ()
    filled: np.ndarray | None = None
    phases: tuple[Phase, ...] = ()
    objects: dict[str, ObjectTrack] = field(default_factory=dict)
    hand_roots: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = ""
    sha256: str = ""
    notes: tuple[str, ...] = ()
    flags: tuple[Flag, ...] = ()

    def __post_init__(self) -> None:
        t = np.asarray(self.times)
        n = t.shape[0] if t.ndim == 1 else -1
        if t.ndim != 1 or n < 1:
            raise TrajectoryError(f"times must be a non-empty 1-D array, got shape {t.shape}")
        if np.any(np.diff(t) <= 0):
            k = int(np.argmax(np.diff(t) <= 0))
            raise TrajectoryError(f"times must strictly increase; sample {k + 1} is not after sample {k}")
        if len(set(self.dof_names)) != len(self.dof_names):
            raise TrajectoryError(f"duplicate DoF names in {list(self.dof_names)}")
        shape = (n, len(self.dof_names))
        if np.shape(self.targets) != shape:
            raise TrajectoryError(f"targets must have shape {shape}, got {np.shape(self.targets)}")
        if np.shape(self.valid) != shape:
            raise TrajectoryError(f"valid must have shape {shape}, got {np.shape(self.valid)}")
        if self.switch is not None and np.shape(self.switch) != (n,):
            raise TrajectoryError(f"switch must have shape ({n},), got {np.shape(self.switch)}")
        if self.root_pose is not None and np.shape(self.root_pose) != (n, 7):
            raise TrajectoryError(f"root_pose must have shape ({n}, 7), got {np.shape(self.root_pose)}")
        for name, pose in self.hand_roots.items():
            if np.shape(pose) != (n, 7):
                raise TrajectoryError(
                    f"hand {name!r} root pose must have shape ({n}, 7), got {np.shape(pose)}"
                )
        if self.hand_roots and self.root_pose is not None:
            raise TrajectoryError("give one hand's root_pose or several hands' hand_roots, not both")
        for name, values in self.channels.items():
            if np.shape(values) != (n,):
                raise TrajectoryError(f"channel {name!r} must have shape ({n},), got {np.shape(values)}")
        unknown = [c for c in self.computed if c not in self.dof_names]
        if unknown:
            raise TrajectoryError(f"computed DoFs {unknown} are not among {list(self.dof_names)}")
        if self.filled is not None and np.shape(self.filled) != shape:
            raise TrajectoryError(f"filled must have shape {shape}, got {np.shape(self.filled)}")
        for phase in self.phases:
            if not 0 <= phase.start < phase.stop <= n:
                raise TrajectoryError(
                    f"phase {phase.name!r} spans frames [{phase.start}, {phase.stop}), outside [0, {n})"
                )
        for name, track in self.objects.items():
            if np.shape(track.pose) != (n, 7):
                raise TrajectoryError(
                    f"object {name!r} pose must have shape ({n}, 7), got {np.shape(track.pose)}"
                )
            for what, arr in (("articulation", track.articulation), ("valid", track.valid)):
                if arr is not None and np.shape(arr) != (n,):
                    raise TrajectoryError(
                        f"object {name!r} {what} must have shape ({n},), got {np.shape(arr)}"
                    )

    @property
    def nframes(self) -> int:
        """Number of samples T."""
        return int(self.times.shape[0])

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, seconds."""
        return float(self.times[-1] - self.times[0])

    @cached_property
    def mean_rate(self) -> float:
        """Mean sampling rate in Hz (samples per second over the duration); 0 for one sample."""
        return (self.nframes - 1) / self.duration if self.nframes > 1 else 0.0

    def phase(self, name: str) -> Phase:
        """The first phase with this name.

        Raises:
            TrajectoryError: If there is none; the message lists the phases there are.
        """
        for phase in self.phases:
            if phase.name == name:
                return phase
        raise TrajectoryError(f"no phase {name!r}; phases are {[p.name for p in self.phases]}")

    def column(self, dof_name: str) -> np.ndarray:
        """Targets of one DoF, shape (T,).

        Raises:
            TrajectoryError: If the trajectory has no such DoF; the message lists the valid names.
        """
        if dof_name not in self.dof_names:
            raise TrajectoryError(f"no DoF {dof_name!r}; DoFs are {list(self.dof_names)}")
        return self.targets[:, self.dof_names.index(dof_name)]
