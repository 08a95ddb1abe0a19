"""Scene composition for simulation: the compiled model, its layout of names and sensors, model summaries.

* :mod:`~handsim.sim.scene.model` — compiling an ``MjSpec`` with MuJoCo's errors made readable;
* :mod:`~handsim.sim.scene.layout` — the ids, addresses and sensor slots of a compiled scene;
* :mod:`~handsim.sim.scene.compiled` — :class:`~handsim.sim.scene.compiled.SimScene`, a compiled scene with
  its
  layout, ready to step;
* :mod:`~handsim.sim.scene.clearance` — where a recording puts the hands, and how deep they pass into the
  static bodies;
* :mod:`~handsim.sim.scene.support` — an object's stand: its footprint, cut back out of the hands' way;
* :mod:`~handsim.sim.scene.settle` — start states without overlap: an articulated object's parts, the hands'
  starting depth.
"""
