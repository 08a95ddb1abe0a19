"""CyberGlove data as used by GraspDB14: sensor layout, calibration, DIP coupling and trial phases.

Sensor layout (:mod:`handsim.glove.sensors`):

* :data:`SENSORS` — the 23 sensors of a motion row, in file order (:class:`GloveSensor`).
* :data:`SENSOR_NAMES` — their names.
* :func:`driven_dofs` — the DoFs the glove drives (every angle negated: ``target = -value``).
* :func:`computed_dofs` — the DoFs the 18-sensor glove does not measure (inferred DIP flexions).
* :func:`discarded_sensors` — sensors that drive no DoF (``I-AA``, ``P-Arch``).

Calibration, raw counts → radians (:mod:`handsim.glove.calibration`):

* :class:`GloveCalibration`, :func:`apply_calibration`, :func:`load_calibration`, :func:`save_calibration`.
* :func:`estimate_calibration` — from a recorded calibration sequence (:data:`CALIBRATION_PROTOCOL`).

DIP coupling (:mod:`handsim.glove.coupling`): :func:`couple_dip` (``DIP = 2/3 PIP`` by default),
:func:`cyberglove_dip` (the relation the GraspDB14 glove software used).

Gap filling (:mod:`handsim.glove.gaps`): :func:`fill_gaps` by the thesis' five methods or linear
interpolation (:data:`GAP_METHODS`), :func:`find_gaps`.

Thumb rest posture (:mod:`handsim.glove.thumb_rest`): :func:`apply_thumb_rest` holds the thumb TMC DoFs
no sensor drives (:data:`THUMB_REST_DOFS`) at a constant posture.

Phases (:mod:`handsim.glove.phases`): :func:`split_by_switch`, :func:`read_phase_annotations`,
:func:`find_annotation_file`, :func:`attach_phases`, :func:`cut`.
"""

from __future__ import annotations

from handsim.glove.calibration import (
    CALIBRATION_PROTOCOL,
    DEFAULT_COUPLING,
    DEFAULT_GAINS,
    AbductionCoupling,
    CalibrationError,
    GloveCalibration,
    ReferencePose,
    apply_calibration,
    estimate_calibration,
    load_calibration,
    save_calibration,
)
from handsim.glove.coupling import CYBERGLOVE, DIP_PIP_RATIO, couple_dip, cyberglove_dip
from handsim.glove.gaps import GAP_METHODS, fill_gaps, find_gaps
from handsim.glove.phases import (
    PhaseAnnotation,
    attach_phases,
    cut,
    find_annotation_file,
    read_phase_annotations,
    split_by_switch,
    switch_segments,
)
from handsim.glove.sensors import (
    SENSOR_NAMES,
    SENSORS,
    GloveSensor,
    computed_dofs,
    discarded_sensors,
    driven_dofs,
)
from handsim.glove.thumb_rest import THUMB_REST_DOFS, apply_thumb_rest, thumb_rest_note

__all__ = [
    "CALIBRATION_PROTOCOL",
    "CYBERGLOVE",
    "DEFAULT_COUPLING",
    "DEFAULT_GAINS",
    "DIP_PIP_RATIO",
    "GAP_METHODS",
    "SENSORS",
    "SENSOR_NAMES",
    "THUMB_REST_DOFS",
    "AbductionCoupling",
    "CalibrationError",
    "GloveCalibration",
    "GloveSensor",
    "PhaseAnnotation",
    "ReferencePose",
    "apply_calibration",
    "apply_thumb_rest",
    "attach_phases",
    "computed_dofs",
    "couple_dip",
    "cut",
    "cyberglove_dip",
    "discarded_sensors",
    "driven_dofs",
    "estimate_calibration",
    "fill_gaps",
    "find_annotation_file",
    "find_gaps",
    "load_calibration",
    "read_phase_annotations",
    "save_calibration",
    "split_by_switch",
    "switch_segments",
    "thumb_rest_note",
]
