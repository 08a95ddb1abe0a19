"""Finger groups of hand links with the hand's prefix of a two-hand scene (``right/index3``)."""

from __future__ import annotations

import pytest

from handsim.datatypes.fingers import (
    FINGER_GROUPS,
    finger_groups,
    finger_of,
    group_of,
    groups_by_hand,
    hand_of,
)


@pytest.mark.parametrize(
    ("link", "hand", "finger"),
    [
        ("right/index3", "right", "index"), ("left/thumb1", "left", "thumb"),
        ("left/pinky2", "left", "little"), ("right/index0", "right", "palm"),
        ("right/wrist", "right", "palm"), ("left/middle_tip", "left", "palm"),
        ("right/RFing_4_Hand", "right", "thumb"), ("left/if_mcp", "left", "index"),
        ("index3", "", "index"), ("th_tmc", "", "thumb"), ("RFing_0_2", "", "little"), ("root", "", "palm"),
    ],
)  # fmt: skip
def test_finger_of_a_link_with_or_without_its_hands_prefix(link, hand, finger):
    assert hand_of(link) == hand
    assert finger_of(link) == finger
    assert group_of(link) == (f"{hand}/{finger}" if hand else finger)


def test_one_hands_groups_are_the_bare_finger_groups_as_before():
    groups = finger_groups(["wrist", "thumb1", "index1", "index2", "pinky3"])
    assert groups == {"thumb": [1], "index": [2, 3], "middle": [], "ring": [], "little": [4], "palm": [0]}
    assert finger_groups([]) == {g: [] for g in FINGER_GROUPS}


def test_two_hands_groups_are_per_hand_in_the_order_of_their_links():
    links = ["right/wrist", "right/index3", "right/thumb2", "left/wrist", "left/index3", "left/pinky1"]
    groups = finger_groups(links)
    assert list(groups) == [f"{hand}/{g}" for hand in ("right", "left") for g in FINGER_GROUPS]
    assert groups["right/index"] == [1] and groups["right/thumb"] == [2] and groups["right/palm"] == [0]
    assert groups["left/index"] == [4] and groups["left/little"] == [5] and groups["left/palm"] == [3]
    assert sum(len(v) for v in groups.values()) == len(links)


def test_groups_by_hand_orders_each_hands_groups_as_recorded_and_others_last():
    assert groups_by_hand(["palm", "zeta", "thumb", "alpha", "index"]) == {
        "": ["thumb", "index", "palm", "alpha", "zeta"]
    }
    names = ["left/index", "right/palm", "right/thumb", "left/thumb", "right/other"]
    assert groups_by_hand(names) == {
        "left": ["left/thumb", "left/index"],
        "right": ["right/thumb", "right/palm", "right/other"],
    }
    assert groups_by_hand([]) == {}
