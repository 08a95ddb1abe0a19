"""Trial kind ``scripted``: a synthetic scripted grasp ``NAME.grasp.json`` (:mod:`handsim.io.scripted`).

Not a recording but a closing motion written for handsim. The hand is the parametric default hand of the
file's ``hand_length``, the object the file's catalogue object unless one is given; its ``grasp`` phase is
the hold (scenario ``glove``, as for GraspDB14).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from handsim.builders import catalog, default_skeleton
from handsim.builders.graspdb_objects import UnknownObjectError
from handsim.errors import HandsimError
from handsim.io.scripted import SYNTHETIC_NOTE, is_scripted_grasp, read_scripted_grasp, scripted_grasp_fields
from handsim.trials.base import LoadedTrial, Trial, TrialObject
from handsim.trials.episodes import add_episodes
from handsim.trials.glove import glove_loaded, parametric_hand
from handsim.trials.kind import TrialKind
from handsim.trials.options import TrialOptions
from handsim.trials.sorting import Sorting, TrialEntry, group_fields, trial_input

if TYPE_CHECKING:
    from handsim.datatypes.trajectory import Trajectory
    from handsim.sim.specs import MetricSpec


def _matches(path: Path) -> bool:
    return path.is_file() and path.name.lower().endswith(".grasp.json")


def _find(path: Path, options: TrialOptions) -> Trial:
    fields = scripted_grasp_fields(path)
    notes = [f"{SYNTHETIC_NOTE}: {path.name}"]
    if options.obj is not None:
        objects = (TrialObject(str(options.obj), "", "given"),)
    else:
        name = fields["object"]
        if name not in catalog.names():
            raise UnknownObjectError(
                f"{path} [object]: unknown object {name!r}; catalogue objects are: "
                f"{', '.join(sorted(catalog.names()))}"
            )
        objects = (TrialObject(name, "", "the scripted grasp's object"),)
        notes.append(f"object {name!r}: named in the scripted grasp")
    hand_length = options.hand_length
    if hand_length is None:
        hand_length = fields["hand_length"]
    else:
        notes.append(
            f"hand length {hand_length:g} m given (the scripted grasp says {fields['hand_length']:g} m)"
        )
    return Trial(
        kind="scripted",
        trajectory_path=str(path),
        skeleton_path=None,
        objects=objects,
        units=options.units,
        density=options.density,
        mass=options.mass,
        hand_length=float(hand_length),
        collision=options.collision or "capsules",
        notes=tuple(notes),
    )


def _load(trial: Trial, metrics: MetricSpec | None, progress: bool) -> LoadedTrial:
    skeleton, hand, hand_text = parametric_hand(trial)
    trajectory = read_scripted_grasp(trial.trajectory_path, skeleton=skeleton)
    return glove_loaded(trial, hand, hand_text, trajectory, metrics, progress)


def _read(trial: Trial) -> Trajectory:
    """The scripted grasp as the trial replays it, without building its scene."""
    return read_scripted_grasp(trial.trajectory_path, skeleton=default_skeleton(trial.hand_length))


def _sort_files(sorting: Sorting) -> None:
    for f in sorting.open_files():
        if not is_scripted_grasp(f):
            continue
        path = sorting.base / f
        try:
            trial = _find(path, TrialOptions())
            fields = scripted_grasp_fields(path)
        except HandsimError as exc:
            sorting.unknown[f] = f"a scripted grasp (.grasp.json), but not a trial: {exc}"
            continue
        meta = group_fields(
            object=trial.objects[0].what, grasp="scripted", synthetic=True, closure=fields["closure"]
        )
        entry = TrialEntry(f, trial, meta, (trial_input("trajectory", path, sorting.base),))
        add_episodes(sorting, entry, _read)


KIND = TrialKind(
    name="scripted",
    label="a scripted grasp",
    files="handsim scripted grasp NAME.grasp.json (synthetic closing motion of the parametric hand)",
    options=frozenset({"obj", "units", "density", "mass", "hand_length", "collision"}),
    brings="it drives the parametric default hand (give a hand length to resize it)",
    matches=_matches,
    find=_find,
    load=_load,
    sort_files=_sort_files,
    read=_read,
)
"""The ``scripted`` kind of trial."""
