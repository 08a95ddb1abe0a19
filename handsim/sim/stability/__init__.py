"""Stability tests of a grip: gravity from several directions, drop tests and soft finger pads.

* :mod:`~handsim.sim.stability.gravity` — :func:`~handsim.sim.stability.gravity.stability_test`, the
  object held against gravity turned in each direction;
* :mod:`~handsim.sim.stability.inputs` — the inputs of that test, checked before any run;
* :mod:`~handsim.sim.stability.drop` — an object dropped on the table settles without a warning;
* :mod:`~handsim.sim.stability.pad` — the soft finger pads' compliance, calibrated to a force and a depth.
"""
