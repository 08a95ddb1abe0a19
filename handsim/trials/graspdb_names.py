"""What a GraspDB14 motion file name says, as the group-by fields of a dataset run (spec ``003_…`` §4.1.2).

:func:`handsim.io.graspdb.filenames.parse_graspdb_filename` decodes the name's fields; this module turns them
into names people group by: the object's catalogue name (Table 4.1 via
:mod:`handsim.builders.graspdb_objects`), the grasp type (Table 3.3, after Feix et al.), the action
(Table 4.2) and the recording scenario (§3.6).
"""

from __future__ import annotations

from dataclasses import dataclass

from handsim.io.graspdb.filenames import GraspDBName


@dataclass(frozen=True)
class GraspType:
    """One grasp type of GraspDB14's controlled object transport (spec Table 3.3).

    Attributes:
        grasp_id: The grasp's number in Feix et al.'s taxonomy (second field of a scenario-3 file name).
        name: The grasp's name as Table 3.3 gives it.
        grasp_class: Table 3.3's group: basic type and opposition (``"power, palm opposition"`` …).
    """

    grasp_id: int
    name: str
    grasp_class: str


_POWER_PALM = "power, palm opposition"
_POWER_PAD = "power, pad opposition"
_INTERMEDIATE_SIDE = "intermediate, side opposition"
_PRECISION_PAD = "precision, pad opposition"
_PRECISION_SIDE = "precision, side opposition"

GRASP_TYPES: dict[int, GraspType] = {
    g.grasp_id: g
    for g in (
        GraspType(1, "Large diameter", _POWER_PALM),
        GraspType(2, "Small diameter", _POWER_PALM),
        GraspType(3, "Medium wrap", _POWER_PALM),
        GraspType(4, "Abducted thumb", _POWER_PALM),
        GraspType(10, "Power disk", _POWER_PALM),
        GraspType(11, "Power sphere", _POWER_PALM),
        GraspType(15, "Fixed hook", _POWER_PALM),
        GraspType(17, "Index finger extension", _POWER_PALM),
        GraspType(30, "Palmar", _POWER_PALM),
        GraspType(18, "Extension type", _POWER_PAD),
        GraspType(26, "Sphere 4 finger", _POWER_PAD),
        GraspType(28, "Sphere 3 finger", _POWER_PAD),
        GraspType(31, "Ring", _POWER_PAD),
        GraspType(16, "Lateral", _INTERMEDIATE_SIDE),
        GraspType(32, "Ventral", _INTERMEDIATE_SIDE),
        GraspType(6, "Prismatic 4 finger", _PRECISION_PAD),
        GraspType(7, "Prismatic 3 finger", _PRECISION_PAD),
        GraspType(8, "Prismatic 2 finger", _PRECISION_PAD),
        GraspType(9, "Palmar pinch", _PRECISION_PAD),
        GraspType(13, "Precision sphere", _PRECISION_PAD),
        GraspType(14, "Tripod", _PRECISION_PAD),
        GraspType(22, "Parallel extension", _PRECISION_PAD),
        GraspType(27, "Quadpod", _PRECISION_PAD),
        GraspType(33, "Inferior pincer", _PRECISION_PAD),
        GraspType(20, "Writing tripod", _PRECISION_SIDE),
    )
}
"""The 25 grasp types of spec Table 3.3 by grasp id."""

ACTIONS: dict[str, tuple[str, str]] = {
    "o_r": ("open", "right"),
    "s_r": ("close", "right"),
    "f_r": ("close tightly", "right"),
    "i_r": ("interact", "right"),
    "o_l": ("open", "left"),
    "s_l": ("close", "left"),
    "f_l": ("close tightly", "left"),
}
"""Spec Table 4.2: action id → (action, leading hand)."""

SCENARIOS: dict[int, str] = {
    1: "uncontrolled object transport",
    2: "object use and interaction",
    3: "controlled object transport",
}
"""The recording scenarios of spec §3.6 by their number (``ex01`` … ``ex03``)."""


def action_label(action_id: str) -> str:
    """The action of a Table 4.2 id for people, e.g. ``"i_r"`` → ``"interact (right hand)"``.

    Args:
        action_id: A Table 4.2 action id.

    Returns:
        The label; an id the table lacks is returned as ``"<id> (not in Table 4.2)"``.
    """
    known = ACTIONS.get(action_id)
    if known is None:
        return f"{action_id} (not in Table 4.2)"
    return f"{known[0]} ({known[1]} hand)"


def graspdb_meta(name: GraspDBName, object_name: str | None) -> dict:
    """The group-by fields of a GraspDB14 trial.

    Args:
        name: The decoded file name.
        object_name: The catalogue name of the object its id names, or None when the id is not in it.

    Returns:
        ``object``, ``grasp`` (Table 3.3 name, None without a grasp id or for an id the table lacks),
        ``grasp_id``, ``grasp_class``, ``action`` (Table 4.2, for people), ``action_id``, ``scenario``
        (§3.6 name), ``scenario_id`` (as written, ``"03-1"``), ``actor`` (``"su04"``), ``sequence`` (None:
        GraspDB14 trials are single grasps), ``object_id``, ``datatype`` and ``trial_counter``.
    """
    grasp = GRASP_TYPES.get(name.grasp_id) if name.grasp_id is not None else None
    return {
        "object": object_name,
        "grasp": None if grasp is None else grasp.name,
        "grasp_id": name.grasp_id,
        "grasp_class": None if grasp is None else grasp.grasp_class,
        "action": None if name.action_id is None else action_label(name.action_id),
        "action_id": name.action_id,
        "scenario": SCENARIOS.get(name.scenario_number, f"scenario {name.scenario_number}"),
        "scenario_id": name.scenario,
        "actor": f"su{name.actor_id:02d}",
        "sequence": None,
        "object_id": name.object_id,
        "datatype": name.datatype,
        "trial_counter": name.trial_id,
    }
