"""Flags: why a replay's numbers mean less than they seem, as plain data.

A flag is raised by the replay's plausibility gates (:func:`handsim.sim.plausibility.replay_flags`) or, before
any replay, by a check of the recording itself (ARCTIC hands that look swapped:
:func:`handsim.trials.arctic_hands.hand_side_check`), which the trajectory carries in
:attr:`handsim.datatypes.trajectory.Trajectory.flags` so that every replay of it reports the flag. A flag with
``invalid`` set makes the replay *not valid*: its numbers are reported but excluded from a dataset's rates.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Flag:
    """Why a replay's numbers mean less than they seem.

    Attributes:
        code: ``"too_few_frames"``, ``"initial_penetration"``, ``"track_jump"``, ``"joint_limits"``, or a
            recording's own flag such as ``"hands_swapped"``.
        invalid: The replay is not valid (its numbers must not enter rates); False for a note.
        reason: One line for people, with the numbers.
        values: The numbers (SI units in the key names), JSON-ready.
    """

    code: str
    invalid: bool
    reason: str
    values: dict = field(default_factory=dict)

    def line(self) -> str:
        """``code: reason`` for people; ``code (a note): reason`` when it does not make the replay invalid."""
        return f"{self.code}{'' if self.invalid else ' (a note)'}: {self.reason}"

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        return {"code": self.code, "invalid": self.invalid, "reason": self.reason, "values": self.values}
