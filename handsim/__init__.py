"""handsim: captured human hand motion (CyberGlove, MANO, Tzionas) as MuJoCo physics.

Data flows one way: ``handsim.io`` readers → plain data (:class:`~handsim.datatypes.skeleton.Skeleton`,
:class:`~handsim.datatypes.trajectory.Trajectory`) → ``handsim.builders`` (``mujoco.MjSpec``) →
``handsim.sim``.
"""

__version__ = "0.1.0"

# Registers handsim/Replay-v0 and handsim/Grasp-v0: imports gymnasium and NumPy, not MuJoCo, and sets no
# environment variable (rendering picks its OpenGL backend when it renders: handsim.viz.headless).
import handsim.envs  # noqa: F401
