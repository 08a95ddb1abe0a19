"""The CyberGlove sensor layout of GraspDB14 recordings, as data.

A GraspDB14 motion row holds 23 sensor values after its time stamp and switch state (spec §4.2.2,
Table 4.3). This module lists them in file order with what each one measures (Table 3.1), whether the
18-sensor CyberGlove used for GraspDB14 measures it, and which skeleton DoF it drives.

The sensor → DoF map reproduces the GraspDB14 MATLAB tools (``constructSensor2JointMap``,
``calcJointTrajectories``) exactly:

* A DoF is named after its skeleton joint with ``-`` replaced by ``_``
  (:func:`handsim.datatypes.skeleton.mj_name`),
  followed by ``_flex`` (rotation about the joint's local x axis), ``_pron`` (local y) or ``_abd``
  (local z).
* Every sensor angle is negated: ``target = -value``.
* ``T-TMCJ`` drives ``th_tmc_pron`` (local **y**). Table 5.1 of the spec says local z, but the MATLAB
  code, which produced the published joint trajectories, uses y; we follow the code.
* ``I-AA`` (unsupported by the glove) and ``P-Arch`` (deactivated in the MATLAB tools) drive no DoF.
  Readers keep their values as extra channels rather than dropping them.
* With the 18-sensor glove, ``I-DIPJ``, ``M-DIPJ``, ``R-DIPJ`` and ``L-DIPJ`` are not measured: the glove
  software infers them from the other joints of the finger, so the DoFs they drive are *computed*.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class GloveSensor:
    """One CyberGlove sensor column of a GraspDB14 motion row.

    Attributes:
        index: 0-based sensor number (spec Table 3.1 / 4.3); the value is token ``7 + index`` of a row.
        name: Sensor denotation as in the GraspDB14 MATLAB tools (``"T-TMCJ"``, ``"I-MCPJ"``, …).
        description: What the sensor monitors (Table 3.1; CyberGlove manual for the sensors that table
            leaves out).
        measured: True if the 18-sensor CyberGlove measures it; False for values the glove software
            infers (the DIP joints) or never supports (``I-AA``, always 0 on this glove).
        joint: Skeleton joint of the GraspDB14 default hand the sensor belongs to (Table 5.1), if any.
        dof: Name of the DoF its (negated) angle drives, or None when the reading is discarded.
        sign: Factor from the file value to the DoF angle: always -1 (``target = -value``).
    """

    index: int
    name: str
    description: str
    measured: bool
    joint: str | None
    dof: str | None
    sign: int = -1

    @property
    def computed(self) -> bool:
        """True if the sensor drives a DoF although the 18-sensor glove does not measure it."""
        return self.dof is not None and not self.measured


SENSORS: tuple[GloveSensor, ...] = (
    GloveSensor(
        0,
        "T-TMCJ",
        "angle of thumb rotating across palm at trapeziometacarpal joint",
        True,
        "th-tmc",
        "th_tmc_pron",
    ),
    GloveSensor(
        1, "T-MCPJ", "flexion/extension at thumb metacarpophalangeal joint", True, "th-mcp", "th_mcp_flex"
    ),
    GloveSensor(2, "T-IPJ", "flexion/extension at thumb interphalangeal joint", True, "th-ip", "th_ip_flex"),
    GloveSensor(3, "TI-AA", "angle between thumb and index finger", True, "th-mcp", "th_mcp_abd"),
    GloveSensor(4, "I-MCPJ", "flexion/extension at index finger MCP joint", True, "if-mcp", "if_mcp_flex"),
    GloveSensor(
        5,
        "I-PIPJ",
        "flexion/extension at index finger proximal interphalangeal joint",
        True,
        "if-pip",
        "if_pip_flex",
    ),
    GloveSensor(
        6,
        "I-DIPJ",
        "flexion/extension at index finger distal interphalangeal joint (inferred on the 18-sensor glove)",
        False,
        "if-dip",
        "if_dip_flex",
    ),
    GloveSensor(
        7,
        "I-AA",
        "absolute abduction of the index finger (unsupported by the glove; Table 4.3 says always 0, "
        "but the sample rad files hold non-zero values)",
        False,
        "if-mcp",
        None,
    ),
    GloveSensor(8, "M-MCPJ", "flexion/extension at middle finger MCP joint", True, "mf-mcp", "mf_mcp_flex"),
    GloveSensor(9, "M-PIPJ", "flexion/extension at middle finger PIP joint", True, "mf-pip", "mf_pip_flex"),
    GloveSensor(
        10,
        "M-DIPJ",
        "flexion/extension at middle finger DIP joint (inferred on the 18-sensor glove)",
        False,
        "mf-dip",
        "mf_dip_flex",
    ),
    GloveSensor(11, "MI-AA", "angle between middle and index fingers", True, "if-mcp", "if_mcp_abd"),
    GloveSensor(12, "R-MCPJ", "flexion/extension at ring finger MCP joint", True, "rf-mcp", "rf_mcp_flex"),
    GloveSensor(13, "R-PIPJ", "flexion/extension at ring finger PIP joint", True, "rf-pip", "rf_pip_flex"),
    GloveSensor(
        14,
        "R-DIPJ",
        "flexion/extension at ring finger DIP joint (inferred on the 18-sensor glove)",
        False,
        "rf-dip",
        "rf_dip_flex",
    ),
    GloveSensor(15, "RM-AA", "angle between ring and middle fingers", True, "rf-mcp", "rf_mcp_abd"),
    GloveSensor(16, "L-MCPJ", "flexion/extension at little finger MCP joint", True, "lf-mcp", "lf_mcp_flex"),
    GloveSensor(17, "L-PIPJ", "flexion/extension at little finger PIP joint", True, "lf-pip", "lf_pip_flex"),
    GloveSensor(
        18,
        "L-DIPJ",
        "flexion/extension at little finger DIP joint (inferred on the 18-sensor glove)",
        False,
        "lf-dip",
        "lf_dip_flex",
    ),
    GloveSensor(19, "LR-AA", "angle between little and ring finger", True, "lf-mcp", "lf_mcp_abd"),
    GloveSensor(20, "P-Arch", "angle of little finger rotating across palm", True, "lf-cmc", None),
    GloveSensor(21, "W-FE", "wrist flexion/extension (pitch)", True, "root", "root_flex"),
    GloveSensor(22, "W-AA", "wrist abduction/adduction (yaw)", True, "root", "root_abd"),
)
"""The 23 sensors in the order of a GraspDB14 motion row."""

SENSOR_NAMES: tuple[str, ...] = tuple(s.name for s in SENSORS)
"""Sensor names in row order."""


def driven_dofs() -> tuple[str, ...]:
    """Names of the DoFs the glove drives, in sensor order (21 DoFs; ``I-AA`` and ``P-Arch`` drive none).

    Returns:
        DoF names such as ``"th_tmc_pron"``, ``"th_mcp_flex"``, … ``"root_abd"``.
    """
    return tuple(s.dof for s in SENSORS if s.dof is not None)


def computed_dofs() -> tuple[str, ...]:
    """DoFs driven by sensors the 18-sensor glove does not measure (the four DIP flexions).

    Returns:
        ``("if_dip_flex", "mf_dip_flex", "rf_dip_flex", "lf_dip_flex")``.
    """
    return tuple(s.dof for s in SENSORS if s.computed and s.dof is not None)


def discarded_sensors() -> tuple[GloveSensor, ...]:
    """Sensors whose readings drive no DoF (``I-AA`` and ``P-Arch``); readers keep them as channels.

    Returns:
        The sensors, in row order.
    """
    return tuple(s for s in SENSORS if s.dof is None)
