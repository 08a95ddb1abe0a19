"""Where a glove recording's object goes: the placement search and everything it is made of.

A glove recording holds no object pose, so the object is placed where it fits in the closing hand and is
gripped best (:func:`handsim.sim.placement.place.place_object`):

* :mod:`~handsim.sim.placement.grasp_frame` — the grasp window and the hand's closing frame;
* :mod:`~handsim.sim.placement.hand_pose` — the hand's frame at rest for the search;
* :mod:`~handsim.sim.placement.poses` and :mod:`~handsim.sim.placement.collide` — candidate poses and the
  collision queries that judge them;
* :mod:`~handsim.sim.placement.search` — the ranked search over poses;
* :mod:`~handsim.sim.placement.grip` — the grip tests that pick the winner;
* :mod:`~handsim.sim.placement.candidates` — candidates and the placement result;
* :mod:`~handsim.sim.placement.robustness` — the ensemble of placements a hold verdict is judged over;
* :mod:`~handsim.sim.placement.cache` — placements on disk, keyed by content.
"""
