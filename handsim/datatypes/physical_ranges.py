"""Documented ranges of the physical parameters a user may give: object mass and density, hand mass.

A value outside its range is refused (:class:`~handsim.errors.OutOfRangeError`) unless the caller forces
it (``force=True``, ``--force`` on the command line): a mass of 1e-9 kg or a density of 1e9 kg/m³ is a
typing or unit error far more often than an intent, and MuJoCo simulates it without complaint. The
sources of every bound are in ``docs/objects.md`` ("Physical ranges").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from handsim.errors import OutOfRangeError


@dataclass(frozen=True)
class PhysicalRange:
    """A closed range of plausible values of one physical parameter.

    Attributes:
        what: The parameter, as messages name it, e.g. ``"object mass"``.
        low: Smallest plausible value, in ``unit``.
        high: Largest plausible value, in ``unit``.
        unit: SI unit of the values.
        basis: What the range spans, for messages, e.g. ``"household objects"``.
    """

    what: str
    low: float
    high: float
    unit: str
    basis: str

    def describe(self) -> str:
        """``"1e-03 to 23 kg (household objects)"``-style text."""
        return f"{self.low:g} to {self.high:g} {self.unit} ({self.basis})"

    def problem(self, value: float, subject: str = "", context: str = "") -> str | None:
        """Why ``value`` is refused, or None when it lies in the range (bounds included).

        Args:
            value: The value, in :attr:`unit`.
            subject: Text before the parameter's name, e.g. ``"object 'mug': "``.
            context: Text after the value, e.g. how it was computed.
        """
        said = f"{subject}{self.what} {value:g} {self.unit}{context}"
        if not math.isfinite(value) or value <= 0:
            return f"{said}: expected a positive number"
        if not self.low <= value <= self.high:
            return f"{said} is outside the plausible {self.describe()}, see docs/objects.md"
        return None

    def check(
        self,
        value: float,
        *,
        force: bool = False,
        hint: str = "pass force=True",
        subject: str = "",
        context: str = "",
    ) -> float:
        """``value`` when it is plausible, or forced and a positive finite number.

        Args:
            value: The value, in :attr:`unit`.
            force: Accept a positive, finite value outside the range.
            hint: How the caller forces a value, for the message.
            subject: Text before the parameter's name in the message.
            context: Text after the value in the message.

        Raises:
            OutOfRangeError: ``value`` is not a positive finite number, or outside the range unforced.
        """
        problem = self.problem(value, subject, context)
        if problem is None:
            return value
        if not math.isfinite(value) or value <= 0:
            raise OutOfRangeError(problem)
        if force:
            return value
        raise OutOfRangeError(f"{problem}; {hint} to use it anyway")


OBJECT_MASS = PhysicalRange("mass", 1e-3, 23.0, "kg", "household objects a hand grasps")
"""1 g (below a table-tennis ball's 2.7 g and the catalogue's 1.6 g business card) to 23 kg (the load
constant of the revised NIOSH lifting equation, Waters et al. 1993: the largest load it recommends
lifting)."""

DENSITY = PhysicalRange("density", 10.0, 11_400.0, "kg/m³", "expanded polystyrene foam to lead")
"""10 kg/m³ (the lightest expanded polystyrene packaging foam; the catalogue's empty cartons are 40 kg/m³
as closed solids) to 11,400 kg/m³ (lead, 11,340 kg/m³, the densest material of household objects)."""

HAND_MASS = PhysicalRange("hand mass", 0.1, 1.0, "kg", "human hands")
"""0.1 to 1.0 kg: the hand is 0.6 % of body mass (Winter 2009; de Leva 1996: 0.61 % men, 0.56 % women),
so this spans body masses from about 17 kg (a four-year-old) to about 167 kg."""


__all__ = ["DENSITY", "HAND_MASS", "OBJECT_MASS", "PhysicalRange"]
