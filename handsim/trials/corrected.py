"""Trial kind ``corrected``: a physically corrected motion (``NAME.corrected.npz``), ``handsim correct``'s.

A corrected trial replays the trial it was corrected from — the same hand, objects and scene, rebuilt from
that trial's files — with the corrected motion: joint targets and wrist poses at the control rate, and the
recorded object tracks. Loading checks that the rebuilt scene is the one corrected (its compiled model's
SHA-256) and that the recording it came from is unchanged (its SHA-256), so that ``handsim replay`` of the
file at its control rate (100 Hz, the default) is bitwise the simulation the correction committed. The file
format is :mod:`handsim.io.corrected`'s; docs/correct.md describes both.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from handsim.datatypes.flags import Flag
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.errors import FormatError, HandsimError, InputFileError
from handsim.io.corrected import CorrectedFile, is_corrected_trial, read_corrected, read_corrected_header
from handsim.trials.base import LoadedTrial, Trial, TrialError, TrialOptions
from handsim.trials.kind import TrialKind
from handsim.trials.sorting import Sorting, TrialEntry, group_fields, trial_input

if TYPE_CHECKING:
    from handsim.sim.specs import MetricSpec

SourceLoader = Callable[[Trial, "MetricSpec | None", bool], LoadedTrial]
"""How a corrected trial loads the trial it was corrected from (the registry's ``load`` of its kind)."""


def source_trial(path: str | Path, header: dict) -> Trial:
    """The trial a corrected file was made from, as its header records it.

    Raises:
        FormatError: The header's ``source.trial`` is not a trial's fields.
    """
    try:
        return Trial.from_dict(header["source"]["trial"])
    except (TrialError, TypeError) as exc:
        raise FormatError(path, f"not a trial's fields: {exc}", field="header.source.trial") from None


def _matches(path: Path) -> bool:
    return path.is_file() and is_corrected_trial(path)


def _find(path: Path, options: TrialOptions) -> Trial:
    header = read_corrected_header(path)
    source = source_trial(path, header)
    method = header["method"]
    return Trial(
        kind="corrected",
        trajectory_path=str(path),
        skeleton_path=source.skeleton_path,
        objects=source.objects,
        density=source.density,
        mass=source.mass,
        collision=source.collision,
        notes=(
            f"corrected by handsim correct from {source.trajectory_path} "
            f"({method.get('method')}, seed {method.get('seed')})",
        ),
    )


def rate_note(header: dict) -> str:
    """The note every corrected trial carries: the rate at which it replays as it was committed."""
    return (
        f"corrected motion at {header['control_rate']:g} Hz: replayed at that rate (the default) it is the "
        "committed simulation, bit for bit"
    )


def corrected_trajectory(corrected: CorrectedFile) -> Trajectory:
    """The corrected motion of a corrected file as a trajectory at its control rate."""
    header, a = corrected.header, corrected.arrays
    hands = header["hands"]
    roots = a["root_pose"]
    objects = {}
    for i, name in enumerate(header["objects"]):
        angle = np.ascontiguousarray(a["object_articulation"][:, i])
        objects[name] = ObjectTrack(
            pose=np.ascontiguousarray(a["object_pose"][:, i]),
            articulation=None if np.all(np.isnan(angle)) else angle,
            valid=np.ascontiguousarray(a["object_valid"][:, i]),
        )
    several = bool(hands) and hands != [""]
    return Trajectory(
        times=a["times"],
        dof_names=tuple(header["dof_names"]),
        targets=a["targets"],
        valid=a["valid"],
        root_pose=np.ascontiguousarray(roots[:, 0]) if hands == [""] else None,
        hand_roots={h: np.ascontiguousarray(roots[:, i]) for i, h in enumerate(hands)} if several else {},
        objects=objects,
        source=corrected.path,
        sha256=corrected.sha256,
        notes=(rate_note(header),),
        flags=tuple(Flag(**f) for f in header["source"].get("flags", [])),
    )


def _loader(load_source: SourceLoader) -> Callable[[Trial, MetricSpec | None, bool], LoadedTrial]:
    def load(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
        corrected = read_corrected(trial.trajectory_path)
        path, header = trial.trajectory_path, corrected.header
        source = source_trial(path, header)
        if not Path(source.trajectory_path).exists():
            raise InputFileError(
                f"{path} [header.source.trial.trajectory_path]: the recording it was corrected from, "
                f"{source.trajectory_path}, is not there; a corrected trial replays in that trial's scene"
            )
        loaded = load_source(source, metrics, progress)
        recorded = header["source"]["sha256"]
        if loaded.trajectory.sha256 != recorded:
            raise TrialError(
                f"{path} [header.source.sha256]: corrected from {source.trajectory_path} with SHA-256 "
                f"{recorded[:16]}…, but that recording now has {loaded.trajectory.sha256[:16]}…; "
                "correct it again"
            )
        if loaded.scene.model_sha256 != header["model_sha256"]:
            raise TrialError(
                f"{path} [header.model_sha256]: the scene built now (model SHA-256 "
                f"{loaded.scene.model_sha256[:16]}…) is not the one corrected "
                f"({header['model_sha256'][:16]}…): handsim, MuJoCo or the trial's files changed since; "
                "correct the recording again"
            )
        return LoadedTrial(
            trial=trial,
            scene=loaded.scene,
            trajectory=corrected_trajectory(corrected),
            hand=loaded.hand,
            objects=loaded.objects,
            notes=(*loaded.notes, rate_note(header)),
            metrics=loaded.metrics,
        )

    return load


def _sort_files(sorting: Sorting) -> None:
    for f in sorting.open_files():
        if not is_corrected_trial(f):
            continue
        path = sorting.base / f
        try:
            trial = _find(path, TrialOptions())
        except HandsimError as exc:
            sorting.unknown[f] = f"a corrected trial (.corrected.npz), but not readable: {exc}"
            continue
        meta = group_fields(object=trial.objects[0].what if trial.objects else None, corrected=True)
        sorting.add(TrialEntry(f, trial, meta, (trial_input("trajectory", path, sorting.base),)))


def corrected_kind(load_source: SourceLoader) -> TrialKind:
    """The ``corrected`` kind, loading the trial a file was corrected from with ``load_source``.

    The registry passes the ``load`` of the source's own kind (this module cannot import the registry,
    which lists this kind).
    """
    return TrialKind(
        name="corrected",
        label="a corrected trial",
        files="handsim corrected trial NAME.corrected.npz (handsim correct's output)",
        options=frozenset(),
        brings="it replays the trial it was corrected from, with that trial's hand, objects and options",
        matches=_matches,
        find=_find,
        load=_loader(load_source),
        sort_files=_sort_files,
    )
