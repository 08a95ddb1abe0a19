"""Which finger a hand link belongs to, from its name, for the per-finger contact curves of a record.

Three naming schemes are known:

* the GraspDB14 skeleton and the parametric default hand: prefixes ``th_``, ``if_``, ``mf_``, ``rf_``,
  ``lf_`` (thumb, index, middle, ring, little);
* MANO (:data:`handsim.io.arctic.mano.FINGERS`): ``thumb1`` … ``pinky3`` (the palm anchors ``index0`` … are
  palm);
* the Tzionas/Ballan right hand: ``RFing_<i>_<j>`` and metacarpal ``RFing_<i>_Hand`` (MuJoCo names: the
  ``.SKEL``'s ``.`` becomes ``_``). The index ``i`` is fixed by the sample's skeleton geometry
  (:data:`TZIONAS_FINGERS`, pinned in ``tests/test_runner.py``): finger 4 is the thumb (two phalanges, its
  metacarpal base far from the knuckle line of the other four), finger 3 is next to it (index), finger 2
  the longest (middle) and finger 0 the shortest (little); the sample's ``.VOI`` lists fingers in this
  order too, little → thumb (``docs/conventions.md``). Only the right hand (``RFing``) is verified.

Every other link (wrist, palm, forearm, any unknown name) counts as ``"palm"``.
"""

from __future__ import annotations

import re

FINGER_GROUPS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "little", "palm")
"""The groups of :func:`finger_of`, in record order."""

GRASPDB_PREFIXES: dict[str, str] = {
    "th": "thumb",
    "if": "index",
    "mf": "middle",
    "rf": "ring",
    "lf": "little",
}
"""GraspDB14 / default hand link-name prefixes (before the first ``_``)."""

MANO_FINGERS: dict[str, str] = {
    "thumb": "thumb",
    "index": "index",
    "middle": "middle",
    "ring": "ring",
    "pinky": "little",
}
"""MANO finger names (link names are the finger followed by the joint number)."""

TZIONAS_FINGERS: dict[int, str] = {0: "little", 1: "ring", 2: "middle", 3: "index", 4: "thumb"}
"""Tzionas/Ballan right hand: ``RFing.<i>`` → finger."""

_TZIONAS = re.compile(r"RFing[._](?P<i>\d+)_(?:\d+|Hand)")
_MANO = re.compile(r"(?P<f>thumb|index|middle|ring|pinky)[1-9]")  # <finger>0: palm anchors


def finger_of(link: str) -> str:
    """The finger group of a hand link.

    Args:
        link: A hand link's name (MuJoCo body name without the ``hand/`` prefix).

    Returns:
        One of :data:`FINGER_GROUPS`; ``"palm"`` for any link that is not a finger's.
    """
    m = _TZIONAS.fullmatch(link)
    if m is not None:
        return TZIONAS_FINGERS.get(int(m["i"]), "palm")
    m = _MANO.fullmatch(link)
    if m is not None:
        return MANO_FINGERS[m["f"]]
    prefix, sep, _ = link.partition("_")
    if sep and prefix in GRASPDB_PREFIXES:
        return GRASPDB_PREFIXES[prefix]
    return "palm"


def finger_groups(links: tuple[str, ...] | list[str]) -> dict[str, list[int]]:
    """Indices of the links in each finger group.

    Args:
        links: Hand link names, in the order of the contact arrays.

    Returns:
        Every group of :data:`FINGER_GROUPS` (in that order) → the indices of its links (possibly empty).
    """
    groups: dict[str, list[int]] = {g: [] for g in FINGER_GROUPS}
    for i, link in enumerate(links):
        groups[finger_of(link)].append(i)
    return groups
