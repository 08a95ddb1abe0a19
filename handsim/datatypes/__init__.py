"""The plain data types every layer above shares, and the math on them.

:mod:`~handsim.datatypes.skeleton` (joints, degrees of freedom, forward kinematics),
:mod:`~handsim.datatypes.trajectory` (times × DoF targets, root and object poses, phases, the recording's
flags), :mod:`~handsim.datatypes.flags` (why a replay's numbers mean less than they seem),
:mod:`~handsim.datatypes.trajectory_ops` (limits, resampling, two hands: the public names of
:mod:`~handsim.datatypes.trajectory_limits`, :mod:`~handsim.datatypes.trajectory_resampling` and
:mod:`~handsim.datatypes.two_hand_trajectory`), :mod:`~handsim.datatypes.mesh`,
:mod:`~handsim.datatypes.object_model`, :mod:`~handsim.datatypes.poses`, :mod:`~handsim.datatypes.rotations`
(the one rotation module, quaternions ``w, x, y, z``), :mod:`~handsim.datatypes.kinematics` (a rotation
split into a chain of hinge angles), :mod:`~handsim.datatypes.fingers` (hand and finger of a link)
and :mod:`~handsim.datatypes.physical_ranges` (plausible masses and densities).

Frozen dataclasses holding NumPy arrays, SI units; nothing here imports MuJoCo or any other handsim layer
(only :mod:`handsim.errors`).
"""
