"""ARCTIC objects as built: a template folder → two parts, a hinge range, colliding parts, a mass.

:func:`arctic_object` reads the template (:func:`handsim.io.arctic.templates.read_arctic_template`) and
applies:

* **Hinge range** (:func:`arctic_hinge_range`): articulation 0 is the template's closed pose (ARCTIC's
  templates are closed at θ = 0 and open towards positive θ). With a recording, the range is the recorded
  range widened by :data:`HINGE_MARGIN` on both sides, never below the closed pose; without one, the
  object's default opening range from :data:`ARCTIC_OBJECTS`.
* **Colliding parts**: the lid collides with its base through explicit contact pairs (``parts_collide``), so
  it rests on the base instead of sinking into it.
* **Mass**: the object's default mass from :data:`ARCTIC_OBJECTS` (sources and assumptions in
  ``docs/objects.md``), spread over the parts by volume; ``mass`` or ``density`` override it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import numpy.typing as npt

from handsim.datatypes.object_model import ObjectModel
from handsim.errors import ModelError
from handsim.io.arctic.templates import read_arctic_template

HINGE_MARGIN = math.radians(10.0)
"""Added to each side of a recorded articulation range, radians: room for the hand to push a lid a little
past where the recording took it without meeting a hard stop."""

CLOSED_POSE = 0.0
"""The articulation of an ARCTIC template's closed pose, radians."""

CLOSED_TOLERANCE = math.radians(2.0)
"""A recorded articulation this far below the closed pose is fitting noise; farther is noted."""

DEFAULT_OPENING = math.pi / 2
"""Opening range of a template that is not one of ARCTIC's 11 objects, radians (an assumption)."""


@dataclass(frozen=True)
class ArcticObjectInfo:
    """What handsim assumes about one of ARCTIC's objects.

    Attributes:
        name: ARCTIC's object name.
        mass: Default mass in kg.
        opening: Default hinge range upper bound in radians (the lower bound is the closed pose, 0).
        what: The real object, as ARCTIC's purchase list names it, or a description.
        mass_basis: Where the mass comes from: a product figure or a stated assumption.
    """

    name: str
    mass: float
    opening: float
    what: str
    mass_basis: str


_TOY = "Small Foot wooden toy kitchen appliance (ARCTIC's purchase list: 'Small Foot Toy Kitchen Set')"

ARCTIC_OBJECTS: dict[str, ArcticObjectInfo] = {
    o.name: o
    for o in (
        ArcticObjectInfo(
            "box", 0.75, math.radians(110.0),
            "Creative Deco A4 wooden box with lid, 33.8 × 24.8 × 10 cm",
            "assumption: 6 mm boards of 450 kg/m³ over the box's 2850 cm² of walls, floor and lid",
        ),
        ArcticObjectInfo(
            "capsulemachine", 0.5, math.radians(90.0), _TOY,
            "assumption: a small hollow toy appliance of plywood/MDF, 0.4–0.6 kg",
        ),
        ArcticObjectInfo(
            "espressomachine", 0.6, math.radians(90.0), _TOY,
            "assumption: a small hollow toy appliance of plywood/MDF, 0.5–0.7 kg",
        ),
        ArcticObjectInfo(
            "ketchup", 0.6, math.radians(180.0),
            "Xucker tomato ketchup, 500 ml bottle with a flip cap",
            "500 ml × 1.15 g/ml (ketchup) + ≈ 25 g squeeze bottle; assumption: full, as bought",
        ),
        ArcticObjectInfo(
            "laptop", 0.85, math.radians(180.0),
            "Eichhorn wooden toy laptop with puzzle, 32 × 20 cm",
            "assumption: a 2 cm base and a 1 cm lid of 32 × 20 cm plywood at 450 kg/m³",
        ),
        ArcticObjectInfo(
            "microwave", 1.0, math.radians(110.0), _TOY,
            "assumption: the largest of the toy appliances, a hollow plywood/MDF box, 0.8–1.2 kg",
        ),
        ArcticObjectInfo(
            "mixer", 0.5, math.radians(60.0), _TOY,
            "assumption: a small hollow toy appliance of plywood/MDF, 0.4–0.6 kg",
        ),
        ArcticObjectInfo(
            "notebook", 0.6, math.radians(180.0),
            "'Autorenplaner' planner book",
            "assumption: ≈ 110 A4 sheets of 80 g/m² paper (0.55 kg) and a card cover",
        ),
        ArcticObjectInfo(
            "phone", 0.1, math.radians(160.0), "flip phone (no purchase link survives)",
            "assumption: flip phones weigh 90–120 g",
        ),
        ArcticObjectInfo(
            "scissors", 0.09, math.radians(60.0),
            "titanium-coated non-stick scissors, 205 mm",
            "assumption: 8-inch steel office scissors weigh 80–100 g",
        ),
        ArcticObjectInfo(
            "waffleiron", 0.5, math.radians(110.0), _TOY,
            "assumption: a small hollow toy appliance of plywood/MDF, 0.4–0.6 kg",
        ),
    )
}  # fmt: skip
"""ARCTIC's 11 objects: default mass and opening range (``docs/objects.md`` has the table with sources)."""


def arctic_hinge_range(
    name: str, articulation: npt.ArrayLike | None = None
) -> tuple[tuple[float, float], str]:
    """The hinge range of an ARCTIC object, radians, with a note saying which rule gave it.

    Args:
        name: The object (template folder name).
        articulation: The recorded articulation in radians (any shape), or None.

    Returns:
        ``(lower, upper)`` and the note.

    Raises:
        ModelError: A recording with non-finite values, or one that never opens above the closed pose.
    """
    if articulation is None:
        info = ARCTIC_OBJECTS.get(name)
        upper = info.opening if info is not None else DEFAULT_OPENING
        what = f"{name}'s default" if info is not None else "the default for objects outside ARCTIC's 11"
        return (CLOSED_POSE, upper), (
            f"hinge range {math.degrees(CLOSED_POSE):.0f}°..{math.degrees(upper):.0f}° ({what}; no recording)"
        )
    art = np.asarray(articulation, dtype=float).reshape(-1)
    if art.size == 0 or not np.all(np.isfinite(art)):
        raise ModelError(f"{name}: the recorded articulation must be finite angles, got {art.size} values")
    lo, hi = float(art.min()), float(art.max())
    lower = max(CLOSED_POSE, lo - HINGE_MARGIN)
    upper = hi + HINGE_MARGIN
    note = (
        f"hinge range {math.degrees(lower):.1f}°..{math.degrees(upper):.1f}°: the recorded "
        f"{math.degrees(lo):.1f}°..{math.degrees(hi):.1f}° ± {math.degrees(HINGE_MARGIN):.0f}°, never below "
        "the closed pose 0°"
    )
    if lo < CLOSED_POSE - CLOSED_TOLERANCE:
        note += (
            f"; the recording goes {math.degrees(CLOSED_POSE - lo):.1f}° below the closed pose, where the "
            "parts would overlap: the hinge stops there"
        )
    return (lower, upper), note


def arctic_object(
    folder: str | Path,
    *,
    articulation: npt.ArrayLike | None = None,
    mass: float | None = None,
    density: float | None = None,
) -> ObjectModel:
    """An ARCTIC template folder as the two-part object handsim builds (see the module notes).

    Args:
        folder: ``…/meta/object_vtemplates/<name>/`` (``top.obj`` + ``bottom.obj``, or ``mesh.obj`` +
            ``parts.json``; millimetres).
        articulation: The recorded articulation (radians) the hinge range is derived from; None: the
            object's default range.
        mass: Total mass in kg, overriding the object's default.
        density: Uniform density in kg/m³ instead of a mass.

    Returns:
        The object: parts ``bottom`` (root) and ``top``, hinge about (0, 0, −1) with its range and
        ``parts_collide``; notes say which range and mass rules applied.

    Raises:
        InputFileError: The folder is missing or is not a template.
        FormatError, MeshError: See :func:`handsim.io.arctic.templates.read_arctic_template`.
        ModelError: Both ``mass`` and ``density``, or a bad recording.
    """
    if mass is not None and density is not None:
        raise ModelError("give mass or density, not both")
    name = Path(folder).name
    info = ARCTIC_OBJECTS.get(name)
    notes = []
    if mass is None and density is None and info is not None:
        mass = info.mass
        notes.append(f"mass {info.mass:g} kg: {name}'s default ({info.mass_basis})")
    model = read_arctic_template(folder, density=density, mass=mass)
    hinge_range, range_note = arctic_hinge_range(name, articulation)
    assert model.hinge is not None  # every template has two parts
    hinge = replace(model.hinge, range=hinge_range, parts_collide=True)
    return replace(model, hinge=hinge, notes=(*model.notes, *notes, range_note))
