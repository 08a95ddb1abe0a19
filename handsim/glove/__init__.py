"""CyberGlove data as used by GraspDB14: the sensor layout and how sensors drive skeleton DoFs.

* :data:`SENSORS` — the 23 sensors of a motion row, in file order (:class:`GloveSensor`).
* :data:`SENSOR_NAMES` — their names.
* :func:`driven_dofs` — the DoFs the glove drives (every angle negated: ``target = -value``).
* :func:`computed_dofs` — the DoFs the 18-sensor glove does not measure (inferred DIP flexions).
* :func:`discarded_sensors` — sensors that drive no DoF (``I-AA``, ``P-Arch``).
"""

from __future__ import annotations

from handsim.glove.sensors import (
    SENSOR_NAMES,
    SENSORS,
    GloveSensor,
    computed_dofs,
    discarded_sensors,
    driven_dofs,
)

__all__ = ["SENSORS", "SENSOR_NAMES", "GloveSensor", "computed_dofs", "discarded_sensors", "driven_dofs"]
