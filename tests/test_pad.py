"""The finger pads' force–penetration relation: the calibration target docs/physics.md cites."""

from __future__ import annotations

import numpy as np
import pytest

from handsim.builders import default_hand
from handsim.errors import ModelError
from handsim.sim.stability.pad import pad_force_curve


@pytest.fixture(scope="module")
def hand():
    return default_hand()


def test_the_default_hands_index_pad_carries_1_n_at_1_5_mm_on_a_rigid_surface(hand):
    assert pad_force_curve(hand, "if_dip", [0.0015])[0] == pytest.approx(1.0, rel=0.01)


def test_the_pad_stiffens_with_depth_like_a_fingertips_pulp(hand):
    depths = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0]) * 1e-3
    forces = pad_force_curve(hand, "if_dip", depths)
    stiffness = np.diff(forces) / np.diff(depths)
    assert np.all(np.diff(forces) > 0) and np.all(np.diff(stiffness) > 0)
    assert forces[0] < 0.2 and forces[-1] > 10.0  # most of the compliance is used below 1 N


def test_a_link_the_hand_lacks_is_an_error_listing_its_links(hand):
    with pytest.raises(ModelError, match=r"the hand has no link 'xx_dip'; its links are \['root', "):
        pad_force_curve(hand, "xx_dip", [0.001])
