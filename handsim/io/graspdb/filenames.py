"""GraspDB14 motion file names (spec §4.1.2): what object, scenario, data type, trial and actor they name.

:func:`parse_graspdb_filename` decodes a name into a :class:`GraspDBName`; :func:`filename_datatype` says
whether a name declares joint angles in radians (``-rad-``) or raw sensor counts (``-raw-``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class GraspDBName:
    """What a GraspDB14 motion (or phase annotation) file name says, spec §4.1.2.

    Attributes:
        object_id: Object grasped or manipulated (Table 4.1), e.g. 1 for the tennis ball.
        scenario: Recording scenario ``exNo`` as written, e.g. ``"01"`` or ``"03-1"``.
        datatype: ``"rad"`` (joint angles in radians) or ``"raw"`` (8-bit sensor counts).
        trial_id: Linear trial counter.
        actor_id: Actor (subject) who performed the task.
        grasp_id: Grasp type after Feix et al. (Table 3.3); present in scenario 3 names.
        action_id: Action (Table 4.2), e.g. ``"i_r"``; present in scenario 2 names.
        annotation: True for a phase annotation file (``…_annot-.txt``).
        prefix: Text before the object id, without its ``_`` (``"r"`` in ``r_01_11_ex03-…``); its meaning
            is not documented in the spec.
    """

    object_id: int
    scenario: str
    datatype: str
    trial_id: int
    actor_id: int
    grasp_id: int | None = None
    action_id: str | None = None
    annotation: bool = False
    prefix: str = ""

    @property
    def scenario_number(self) -> int:
        """The scenario as a number: 1, 2 or 3 (``"03-1"`` → 3)."""
        return int(self.scenario.split("-")[0])


_NAME_RE = re.compile(
    r"""
    (?:(?P<prefix>[a-z]+)_)?             # optional prefix, e.g. "r_"
    (?P<obj>\d+)                         # object id
    (?:_(?P<grasp>\d+)|_(?P<action>[a-z]_[a-z]))?   # grasp id (scenario 3) or action id (scenario 2)
    _ex(?P<ex>\d+(?:-\d+)?)              # scenario, e.g. 03 or 03-1
    -(?P<dtype>rad|raw)
    -(?P<trial>\d+)
    -grasp-su(?P<actor>\d+)
    (?P<annot>_annot-)?
    (?:\.txt)?
    """,
    re.IGNORECASE | re.VERBOSE,
)


def parse_graspdb_filename(name: str | Path) -> GraspDBName | None:
    """Decode a GraspDB14 motion file name (spec §4.1.2).

    Recognised forms (``.txt`` optional, case ignored, any folder part ignored)::

        <objID>_ex<exNo>-<datatype>-<trialID>-grasp-su<actorID>.txt              scenario 1
        <objID>_<actionID>_ex<exNo>-<datatype>-<trialID>-grasp-su<actorID>.txt   scenario 2
        <objID>_<graspID>_ex<exNo>-<datatype>-<trialID>-grasp-su<actorID>.txt    scenario 3

    optionally with a prefix such as ``r_`` before the object id, and with ``_annot-`` before the
    extension for a phase annotation file. Whether a grasp or an action id is present is read from the
    name, not inferred from the scenario number.

    Args:
        name: A file name or path.

    Returns:
        The decoded name, or None when the name does not follow the pattern (not an error: any file may
        be read, whatever its name).
    """
    m = _NAME_RE.fullmatch(Path(name).name)
    if m is None:
        return None
    return GraspDBName(
        object_id=int(m["obj"]),
        scenario=m["ex"],
        datatype=m["dtype"].lower(),
        trial_id=int(m["trial"]),
        actor_id=int(m["actor"]),
        grasp_id=int(m["grasp"]) if m["grasp"] else None,
        action_id=m["action"].lower() if m["action"] else None,
        annotation=m["annot"] is not None,
        prefix=(m["prefix"] or "").lower(),
    )


# --------------------------------------------------------------------------------------------------
# Motion files


def filename_datatype(path: str | Path) -> str | None:
    """What a file name says the values are: ``"rad"``, ``"raw"``, or None when it does not say.

    Args:
        path: A file name or path; a GraspDB14 name (:func:`parse_graspdb_filename`) or any name holding
            ``-rad-`` or ``-raw-`` (case ignored).

    Returns:
        ``"rad"``, ``"raw"`` or None.
    """
    parsed = parse_graspdb_filename(path)
    if parsed is not None:
        return parsed.datatype
    lowered = Path(path).name.lower()
    kinds = [k for k in ("rad", "raw") if f"-{k}-" in lowered]
    return kinds[0] if len(kinds) == 1 else None


__all__ = ["GraspDBName", "filename_datatype", "parse_graspdb_filename"]
