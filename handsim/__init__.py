"""handsim: captured human hand motion (CyberGlove, MANO, Tzionas) as MuJoCo physics.

Data flows one way: ``handsim.io`` readers → plain data (:class:`~handsim.datatypes.skeleton.Skeleton`,
:class:`~handsim.datatypes.trajectory.Trajectory`) → ``handsim.builders`` (``mujoco.MjSpec``) →
``handsim.sim``.
"""

# Registers handsim/Replay-v0 and handsim/Grasp-v0: imports gymnasium and NumPy, not MuJoCo, and sets no
# environment variable (rendering picks its OpenGL backend when it renders: handsim.viz.headless).
import handsim.envs  # noqa: F401
from handsim.version import __version__ as __version__
