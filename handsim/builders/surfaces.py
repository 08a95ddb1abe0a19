"""How each kind of surface touches another: skin, objects, the environment (MuJoCo contact parameters).

MuJoCo takes a contact's friction, ``condim``, ``solref`` and ``solimp`` from the geom of higher
``priority``, and combines them (friction by maximum, the solver parameters by average) when the priorities
are equal. handsim gives skin and the environment (table, floor) priority 1 and objects priority 0, so:

* a hand–object contact is skin against the object: skin's friction and skin's soft pad;
* an object–table contact uses the table's friction;
* an object–object contact (two parts of an articulated object, or two objects) uses the objects' own.

Every value and its source is in ``docs/physics.md``; :func:`handsim.sim.stability.pad.pad_force_curve`
measures the
pad's force–penetration relation the way the literature measures a fingertip's: pressed on a rigid surface.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

CONTACT_CONDIM = 4
"""Sliding and torsional friction (no rolling friction): a pinched object resists spinning about the contact
normal, as a soft fingertip does."""


@dataclass(frozen=True)
class Surface:
    """The contact parameters a kind of surface brings (MuJoCo geom attributes).

    Attributes:
        sliding: Sliding friction coefficient.
        torsional: Torsional friction, m (torque per unit normal force about the contact normal).
        priority: MuJoCo geom priority: the higher one's parameters are used for a contact.
        solref: (time constant s, damping ratio), or None for MuJoCo's default.
        solimp: (dmin, dmax, width m, midpoint, power), or None for MuJoCo's default.
        margin: How far outside the collision geometry the surface's rest (undeformed) surface lies, m:
            MuJoCo's geom ``margin``, from which the contact's impedance counts penetration (0: the
            geometry is the rest surface).
    """

    sliding: float
    torsional: float
    priority: int = 0
    solref: tuple[float, float] | None = None
    solimp: tuple[float, float, float, float, float] | None = None
    margin: float = 0.0

    @property
    def friction(self) -> list[float]:
        """MuJoCo's geom ``friction`` (sliding, torsional, rolling); rolling is unused with ``condim`` 4."""
        return [self.sliding, self.torsional, 0.0]


PAD_SOLIMP = (0.65, 0.95, 0.003, 0.5, 2.0)
"""Skin: impedance rises from 0.65 to 0.95 over 3 mm of penetration, so that the pad stiffens with depth
like a fingertip's pulp (exponential force–displacement: Pawluk & Howe 1999)."""
PAD_SOLREF = (0.0172, 1.0)
"""Skin: time constant (s) calibrated so that the default hand's index pad pressed on a rigid surface carries
1 N at 1.5 mm of penetration (``docs/physics.md``), critically damped."""

SKIN = Surface(sliding=1.0, torsional=0.0025, priority=1, solref=PAD_SOLREF, solimp=PAD_SOLIMP)
"""The hand's collision geoms: skin against household materials, soft finger pads."""
FITTED_SKIN_OFFSET = 0.0015
"""Hands whose surface was fitted to observed skin (the Tzionas/Ballan hands): the pad's rest surface lies
this far outside the fitted mesh, m. Such a fit puts the mesh where the *compressed* skin touched the object
(the fitting refuses interpenetration), so a pad whose rest surface were the mesh itself would carry almost no
force at the recorded pose; with this offset it carries the pad's calibrated 1 N per contact (1.5 mm,
:data:`PAD_SOLREF`). Measured on Tzionas sequence 20 (``docs/physics.md``): offset 0 / 1 / 1.5 / 2 mm keeps
the cube within 1 cm of its track in 40 / 74 / 76 / 76 % of frames (mean drift 26.5 / 10.5 / 10.5 /
10.1 mm)."""

FITTED_SKIN = replace(SKIN, margin=FITTED_SKIN_OFFSET)
"""Skin of a hand whose surface was fitted to observations: :data:`SKIN` with the rest offset
:data:`FITTED_SKIN_OFFSET`. Hands sized from proportions or driven by a sensor glove (the default hand's
capsules, GraspDB14 skeletons, MANO) keep :data:`SKIN`: their geometry is the undeformed finger."""
OBJECT = Surface(sliding=0.5, torsional=0.001)
"""Objects against each other (hard materials; skin and the environment bring their own)."""
ENVIRONMENT = Surface(sliding=0.4, torsional=0.001, priority=1)
"""The table and the floor: a laminate or wood table top against the objects set on it."""
