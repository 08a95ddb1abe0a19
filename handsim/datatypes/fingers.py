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

In a scene with several hands (ARCTIC's, :mod:`handsim.sim.arctic_scene`) a link's name starts with its hand's
name, ``right/index3``: :func:`hand_of` gives the hand, :func:`finger_of` the finger, and the groups of
:func:`finger_groups` are per hand, ``right/index`` … ``left/palm``. One hand's links have no prefix and its
groups are the bare :data:`FINGER_GROUPS`, as they always were.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

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


def hand_of(link: str) -> str:
    """The hand a link belongs to: its name's prefix before ``/`` (``"right"`` of ``"right/index3"``).

    Args:
        link: A hand link's name (MuJoCo body name without the ``hand/`` prefix).

    Returns:
        The hand's name in a scene with several hands; ``""`` for a link of a one-hand scene.
    """
    hand, sep, _ = link.partition("/")
    return hand if sep else ""


def finger_of(link: str) -> str:
    """The finger group of a hand link, whichever hand it belongs to (:func:`hand_of` tells that).

    Args:
        link: A hand link's name (MuJoCo body name without the ``hand/`` prefix), with its hand's prefix in
            a scene with several hands (``right/index3``).

    Returns:
        One of :data:`FINGER_GROUPS`; ``"palm"`` for any link that is not a finger's.
    """
    hand = hand_of(link)
    link = link[len(hand) + 1 :] if hand else link
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


def group_of(link: str) -> str:
    """The per-hand finger group of a link: ``"index"`` of one hand, ``"right/index"`` in a two-hand scene."""
    hand = hand_of(link)
    return f"{hand}/{finger_of(link)}" if hand else finger_of(link)


def finger_groups(links: tuple[str, ...] | list[str]) -> dict[str, list[int]]:
    """Indices of the links in each finger group, per hand.

    Args:
        links: Hand link names, in the order of the contact arrays.

    Returns:
        Every group of :data:`FINGER_GROUPS` (in that order) → the indices of its links (possibly empty); with
        several hands, each hand's groups ``<hand>/<group>``, hands in the order their links come.
    """
    hands = list(dict.fromkeys(hand_of(link) for link in links)) or [""]
    groups: dict[str, list[int]] = {f"{hand}/{g}" if hand else g: [] for hand in hands for g in FINGER_GROUPS}
    for i, link in enumerate(links):
        groups[group_of(link)].append(i)
    return groups


def groups_by_hand(names: Iterable[str]) -> dict[str, list[str]]:
    """Finger-group names (a record's ``contacts_per_finger`` keys) per hand, each hand's in record order.

    Args:
        names: Group names as :func:`finger_groups` makes them (``"thumb"``, or ``"right/thumb"``), and any
            others.

    Returns:
        Hand (``""`` for one hand's groups), in the order the names first name it → its group names: those
        of :data:`FINGER_GROUPS` in that order, then any others sorted.
    """
    rank = {g: i for i, g in enumerate(FINGER_GROUPS)}
    hands: dict[str, list[str]] = {}
    for name in dict.fromkeys(names):
        hands.setdefault(hand_of(name), []).append(name)

    def order(name: str) -> tuple[int, str]:
        bare = name.partition("/")[2] if hand_of(name) else name
        return (rank.get(bare, len(rank)), "" if bare in rank else name)

    return {hand: sorted(group, key=order) for hand, group in hands.items()}
