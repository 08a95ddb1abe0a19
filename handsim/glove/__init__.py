"""CyberGlove data as used by GraspDB14: sensor layout, calibration, DIP coupling and trial phases.

Sensor layout (:mod:`handsim.glove.sensors`):

* :data:`SENSORS` — the 23 sensors of a motion row, in file order (:class:`GloveSensor`).
* :data:`SENSOR_NAMES` — their names.
* :func:`driven_dofs` — the DoFs the glove drives (every angle negated: ``target = -value``).
* :func:`computed_dofs` — the DoFs the 18-sensor glove does not measure (inferred DIP flexions).
* :func:`discarded_sensors` — sensors that drive no DoF (``I-AA``, ``P-Arch``).

Calibration, raw counts → radians (:mod:`handsim.glove.calibration`):

* :class:`GloveCalibration`, :func:`apply_calibration`; its JSON files are written and read by
  :mod:`handsim.io.graspdb.calibration` (``save_calibration``, ``load_calibration``).
* :func:`estimate_calibration` — from a recorded calibration sequence (:data:`CALIBRATION_PROTOCOL`,
  :mod:`handsim.glove.calibration_estimation`).

DIP coupling (:mod:`handsim.glove.coupling`): :func:`couple_dip` (``DIP = 2/3 PIP`` by default),
:func:`cyberglove_dip` (the relation the GraspDB14 glove software used).

Gap filling (:mod:`handsim.glove.gaps`): :func:`fill_gaps` by the thesis' five methods or linear
interpolation (:data:`GAP_METHODS`), :func:`find_gaps`.

Thumb rest posture (:mod:`handsim.glove.thumb_rest`): :func:`apply_thumb_rest` holds the thumb TMC DoFs
no sensor drives (:data:`THUMB_REST_DOFS`) at a constant posture.

Phases (:mod:`handsim.glove.phases`, on plain data): :func:`split_by_switch`, :func:`switch_segments`,
:class:`PhaseAnnotation` and :class:`AnnotationMatch`, :func:`with_phases`, :func:`cut`. The GraspDB14
phase annotation files are read, found beside a recording and matched to its frames by
:mod:`handsim.io.graspdb.annotations` (``read_phase_annotations``, ``find_annotation_file``,
``match_annotation``, ``attach_phases``).

Spikes (:mod:`handsim.glove.spikes`): :func:`find_spikes`, :func:`remove_spikes` (single-sample jumps beyond
:data:`MAX_JOINT_SPEED` that revert, marked invalid and filled); :mod:`handsim.glove.checks` runs the
annotation and spike checks on a recording.

Grasp episodes (:mod:`handsim.glove.segmentation`): :func:`segment_grasps` turns a recording into
:class:`GraspEpisode` s (approach, closure, hold, release; truncated or not; from the annotation or found
automatically on the summed finger flexion by :mod:`handsim.glove.grasp_hysteresis`),
:class:`GraspSegmentation`; a calibration sequence is recognised by :func:`recognise_calibration_sequence`
(:mod:`handsim.glove.calibration_sequence`) and has none.
"""

from __future__ import annotations

from handsim.glove.calibration import (
    DEFAULT_COUPLING,
    DEFAULT_GAINS,
    AbductionCoupling,
    CalibrationError,
    GloveCalibration,
    apply_calibration,
)
from handsim.glove.calibration_estimation import CALIBRATION_PROTOCOL, ReferencePose, estimate_calibration
from handsim.glove.calibration_sequence import CalibrationSequence, recognise_calibration_sequence
from handsim.glove.coupling import CYBERGLOVE, DIP_PIP_RATIO, couple_dip, cyberglove_dip
from handsim.glove.gaps import GAP_METHODS, fill_gaps, find_gaps
from handsim.glove.phases import (
    AnnotationMatch,
    PhaseAnnotation,
    cut,
    split_by_switch,
    switch_segments,
    with_phases,
)
from handsim.glove.segmentation import GraspEpisode, GraspSegmentation, segment_grasps
from handsim.glove.sensors import (
    SENSOR_NAMES,
    SENSORS,
    GloveSensor,
    computed_dofs,
    discarded_sensors,
    driven_dofs,
)
from handsim.glove.spikes import MAX_JOINT_SPEED, Spike, find_spikes, remove_spikes
from handsim.glove.thumb_rest import THUMB_REST_DOFS, apply_thumb_rest, thumb_rest_note

__all__ = [
    "CALIBRATION_PROTOCOL",
    "CYBERGLOVE",
    "DEFAULT_COUPLING",
    "DEFAULT_GAINS",
    "DIP_PIP_RATIO",
    "GAP_METHODS",
    "MAX_JOINT_SPEED",
    "SENSORS",
    "SENSOR_NAMES",
    "THUMB_REST_DOFS",
    "AbductionCoupling",
    "AnnotationMatch",
    "CalibrationError",
    "CalibrationSequence",
    "GloveCalibration",
    "GloveSensor",
    "GraspEpisode",
    "GraspSegmentation",
    "PhaseAnnotation",
    "ReferencePose",
    "Spike",
    "apply_calibration",
    "apply_thumb_rest",
    "computed_dofs",
    "couple_dip",
    "cut",
    "cyberglove_dip",
    "discarded_sensors",
    "driven_dofs",
    "estimate_calibration",
    "fill_gaps",
    "find_gaps",
    "find_spikes",
    "recognise_calibration_sequence",
    "remove_spikes",
    "segment_grasps",
    "split_by_switch",
    "switch_segments",
    "thumb_rest_note",
    "with_phases",
]
