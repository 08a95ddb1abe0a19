"""The one list of trial options: what a user may give besides the recording, each with how it is named.

:class:`TrialOptions` is that list. Each of its fields carries an :class:`OptionSpec` in its metadata: how
messages name it, the ``handsim`` command-line flag that gives it and that flag's help, so that
:func:`~handsim.trials.find_trial`, each kind's :attr:`~handsim.trials.kind.TrialKind.options`, the refusal
messages and the command line (:func:`handsim.cli._common.add_trial_options`) all read the same list.

This module imports nothing heavy: the command line builds its options from it before any command runs.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from handsim.datatypes.physical_ranges import DENSITY, OBJECT_MASS

if TYPE_CHECKING:
    from handsim.datatypes.physical_ranges import PhysicalRange

HAND_COLLISIONS = ("capsules", "mesh")
"""Hand collision shapes: capsules and a convex palm, or per-bone hulls of a skinned mesh."""

SPEC = "option"
"""The key of a :class:`TrialOptions` field's metadata holding its :class:`OptionSpec`."""


def parse_positive_number(text: str) -> float:
    """``text`` as a finite number > 0 (lengths, masses, densities).

    Whether the value is plausible (a hand length in metres, a household object's mass) is the builder's to
    say; this refuses only what is no quantity at all.

    Raises:
        ValueError: Not a number, or not finite and > 0 (the message says what was given).
    """
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"expected a finite number > 0, got {text}")
    return value


def parse_thumb_rest(text: str) -> tuple[float, float]:
    """``ABD,FLEX`` as two finite angles in degrees (the joint limits are the loader's to check).

    Raises:
        ValueError: Not two finite numbers separated by a comma.
    """
    try:
        values = tuple(float(p) for p in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise ValueError(f"expected ABD,FLEX: two angles in degrees, got {text!r}")
    return values[0], values[1]


def parse_grasp(text: str) -> int:
    """``text`` as a grasp episode number, 1-based (as ``handsim inspect`` lists them).

    Raises:
        ValueError: Not a whole number ≥ 1.
    """
    try:
        value = int(text)
    except ValueError:
        raise ValueError(f"expected a grasp episode number (1, 2 …), got {text!r}") from None
    if value < 1:
        raise ValueError(f"expected a grasp episode number ≥ 1, got {value}")
    return value


@dataclass(frozen=True)
class OptionSpec:
    """How a trial option is named in messages and given on the command line.

    Attributes:
        label: The option in messages, with an article (``"an object mass"``).
        flag: Its command-line flag (``"--mass"``).
        help: The flag's help text.
        metavar: The flag's value in the usage, or None for argparse's default (the choices).
        parse: Turns the flag's text into the value (raising ``ValueError`` with the message to show), or
            None to keep the text.
        choices: The values the flag accepts, or None for any.
        value_range: A documented range the value is checked against after parsing (``--force`` accepts a
            value outside it), or None.
        exclusive: Options with the same non-empty name exclude each other (one command-line group).
        switch: A flag without a value that sets the option to True.
        per_kind: Whether each kind chooses to take it (:attr:`~handsim.trials.kind.TrialKind.options`);
            False for the options :func:`~handsim.trials.find_trial` judges for every kind itself (``force``
            applies to every kind's objects, ``grasp`` to the glove kinds).
    """

    label: str
    flag: str
    help: str
    metavar: str | None = None
    parse: Callable[[str], Any] | None = None
    choices: tuple[str, ...] | None = None
    value_range: PhysicalRange | None = None
    exclusive: str = ""
    switch: bool = False
    per_kind: bool = True


def _spec(label: str, flag: str, help: str, **spec: Any) -> dict[str, OptionSpec]:
    """A :class:`TrialOptions` field's metadata: its :class:`OptionSpec`."""
    return {SPEC: OptionSpec(label, flag, help, **spec)}


@dataclass(frozen=True)
class TrialOptions:
    """What a user may give besides the recording (the ``handsim replay`` options); None: not given.

    Attributes:
        skeleton: The hand's skeleton file (GraspDB14: ``.xmlskel`` or ``.SKEL``, default the parametric
            hand; Tzionas: must be the motion's own ``.SKEL`` if given).
        obj: The object: a catalogue name or a mesh file (GraspDB14: default the object whose id the file
            name carries; scripted grasp: default the file's object).
        calibration: A glove calibration JSON (raw-count GraspDB14 recordings).
        units: A mesh-file object's units, ``"m"`` or ``"mm"``.
        density: Object density in kg/m³ instead of the objects' own.
        mass: Object mass in kg instead of the objects' own.
        hand_length: Parametric default hand's length, m (default 0.19; a scripted grasp's own); only
            without a skeleton.
        collision: Hand collision shapes, one of :data:`HAND_COLLISIONS` (default ``"capsules"``; ``"mesh"``
            for skinned skeletons and MANO hands).
        thumb_rest: Glove recordings: ``(abduction, flexion)`` in degrees at which to hold the thumb TMC
            DoFs no glove sensor drives (:func:`handsim.glove.thumb_rest.apply_thumb_rest`; default: left
            at 0, as the GraspDB14 tools do).
        force: Accept an object density or mass outside its documented range (every kind's objects).
        mano_dir: The folder with the user's ``MANO_RIGHT.pkl`` and ``MANO_LEFT.pkl`` (ARCTIC; default
            ``$HANDSIM_MANO_DIR``).
        templates: ARCTIC object templates folder (``<object>/`` inside), instead of the sequence's
            ``meta/object_vtemplates/``.
        grasp: Glove recordings (GraspDB14, scripted grasps): replay this grasp episode (1-based, as
            :func:`~handsim.trials.registry.grasp_episodes` and ``handsim inspect`` list them), the
            recording cut to it; None: the whole recording.
    """

    skeleton: str | Path | None = field(default=None, metadata=_spec(
        "a skeleton", "--skeleton", "GraspDB14: the hand (.xmlskel or .SKEL)", metavar="SKELETON_FILE",
    ))  # fmt: skip
    obj: str | Path | None = field(default=None, metadata=_spec(
        "an object", "--object", "GraspDB14: a catalogue name or a mesh file (give --units)",
        metavar="NAME|MESH",
    ))  # fmt: skip
    calibration: str | Path | None = field(default=None, metadata=_spec(
        "a calibration", "--calibration", "GraspDB14: calibration of a raw-count recording", metavar="JSON",
    ))  # fmt: skip
    units: str | None = field(default=None, metadata=_spec(
        "mesh units", "--units", "units of a mesh file given as --object", choices=("m", "mm"),
    ))  # fmt: skip
    density: float | None = field(default=None, metadata=_spec(
        "an object density", "--density", f"object density instead of its own, {DENSITY.describe()}",
        metavar="KG_M3", value_range=DENSITY, exclusive="object mass",
    ))  # fmt: skip
    mass: float | None = field(default=None, metadata=_spec(
        "an object mass", "--mass", f"total object mass instead of a density, {OBJECT_MASS.describe()}",
        metavar="KG", value_range=OBJECT_MASS, exclusive="object mass",
    ))  # fmt: skip
    hand_length: float | None = field(default=None, metadata=_spec(
        "a hand length", "--hand-length",
        "GraspDB14 without --skeleton: parametric hand length, wrist crease to middle fingertip (0.19)",
        metavar="M", parse=parse_positive_number,
    ))  # fmt: skip
    collision: str | None = field(default=None, metadata=_spec(
        "a hand collision shape", "--collision",
        "hand collision shapes (default capsules; mesh: per-bone hulls of a skinned .SKEL or MANO hand)",
        choices=HAND_COLLISIONS,
    ))  # fmt: skip
    thumb_rest: tuple[float, float] | None = field(default=None, metadata=_spec(
        "a thumb rest posture", "--thumb-rest",
        "GraspDB14: hold the thumb TMC DoFs no glove sensor drives (th_tmc_abd, th_tmc_flex) at these angles "
        "in degrees (default: 0,0 as the GraspDB14 tools; see docs/cyberglove.md)",
        metavar="ABD,FLEX", parse=parse_thumb_rest,
    ))  # fmt: skip
    force: bool = field(default=False, metadata=_spec(
        "forcing a value out of range", "--force",
        "accept a mass or density outside its documented range (docs/objects.md)",
        switch=True, per_kind=False,
    ))  # fmt: skip
    mano_dir: str | Path | None = field(default=None, metadata=_spec(
        "a MANO model folder", "--mano-dir",
        "ARCTIC: the folder with your MANO_RIGHT.pkl and MANO_LEFT.pkl (default: $HANDSIM_MANO_DIR)",
        metavar="DIR",
    ))  # fmt: skip
    templates: str | Path | None = field(default=None, metadata=_spec(
        "an ARCTIC templates folder", "--templates",
        "ARCTIC: object templates folder (<object>/ inside), not the root's meta/object_vtemplates",
        metavar="DIR",
    ))  # fmt: skip
    grasp: int | None = field(default=None, metadata=_spec(
        "a grasp episode", "--grasp",
        "glove recordings: replay grasp episode K only, with every detail (1-based, as `handsim inspect` "
        "lists them; default: judge every complete episode, one line each)",
        metavar="K", parse=parse_grasp, per_kind=False,
    ))  # fmt: skip


def option_names() -> tuple[str, ...]:
    """The names of the trial options, in :class:`TrialOptions`' order."""
    return tuple(f.name for f in dataclasses.fields(TrialOptions))


def option_spec(name: str) -> OptionSpec:
    """The :class:`OptionSpec` of the trial option ``name``.

    Raises:
        KeyError: ``name`` is no trial option (the message lists them).
    """
    for f in dataclasses.fields(TrialOptions):
        if f.name == name:
            return f.metadata[SPEC]
    raise KeyError(f"no trial option {name!r}; expected one of {list(option_names())}")


def given_options(options: TrialOptions) -> tuple[str, ...]:
    """The names of the options given: those not None (``force``: those not False)."""
    values = {f.name: getattr(options, f.name) for f in dataclasses.fields(options)}
    return tuple(name for name, value in values.items() if value is not None and value is not False)
