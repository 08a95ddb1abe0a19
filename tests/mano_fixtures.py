"""Synthetic MANO model files and ARCTIC sequence files with the real files' structure.

The MANO model files are licensed and absent here, so :func:`write_synthetic_mano_pkl` writes a small
stand-in with the same layout as ``MANO_RIGHT.pkl``: a pickled dict whose ``shapedirs`` is a
``chumpy.ch.Ch`` object and whose ``J_regressor`` is a ``scipy.sparse.csc.csc_matrix``, plus numpy arrays
and the non-array entries a real file carries. The two classes are fakes registered in ``sys.modules``
only while pickling, so the file references ``chumpy.ch`` / ``scipy.sparse.csc`` like a real one while
chumpy is never installed or imported.

Geometry: the bundled mean-shape joints; around each joint a ring of 6 vertices (the joint regressor row
of the joint: random convex weights over them); around each bone a blob of vertices skinned mostly to it;
the five fingertip vertices (MANO ids 744/320/443/554/671) just beyond each finger's last joint, skinned
fully to it. Shape and pose blend shapes and the PCA basis are random but seeded; the mean pose
``hands_mean`` is a relaxed, slightly curled hand like MANO's (finger flexion about +z on the right hand).
The left model is the right one of the same seed mirrored in x, as MANO's is: vertices and joints x → −x,
faces reversed, ``hands_mean`` mirrored (axis-angle (x, y, z) → (x, −y, −z)); its ``shapedirs`` are the
right's unchanged, like the real ``MANO_LEFT.pkl`` (whose x shape directions are known not to be mirrored,
smplx issue #48).

ARCTIC sequences (:func:`arctic_hand_params`, :func:`write_arctic_mano_npy`, :func:`arctic_object_values`)
are written in exactly the real layout (``../shared/data/SOURCES.md``): a pickled ``{'right', 'left'}`` dict,
float32 arrays, ``shape`` (10,), ``fitting_err`` a plain Python list of N floats; the world is z-up with the
hands about 1 m up around the object; object rows are float32 [articulation rad, axis-angle, translation mm].
"""

from __future__ import annotations

import contextlib
import io
import json
import pickle
import sys
import types
from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from handsim.datatypes.skeleton import mj_name
from handsim.io.arctic.mano import MEAN_JOINTS_FILE
from handsim.sim import compile_spec

PARENTS = (-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 0, 10, 11, 0, 13, 14)
NAMES = ("wrist", *(f"{f}{k}" for f in ("index", "middle", "pinky", "ring", "thumb") for k in (1, 2, 3)))
TIP_IDS = {"thumb": 744, "index": 320, "middle": 443, "ring": 554, "pinky": 671}
RING_RADIUS = 0.004  # m
BLOB_RADIUS = 0.006  # m


def mean_joints(side: str = "right") -> np.ndarray:
    """The bundled mean-shape joints (mirrored in x for the left hand), shape (16, 3)."""
    table = json.loads(MEAN_JOINTS_FILE.read_text())
    joints = np.array(table["rest_joint_positions"], dtype=float)
    return joints * np.array([-1.0, 1.0, 1.0]) if side == "left" else joints


MIRROR_AA = np.array([1.0, -1.0, -1.0])
"""An axis-angle rotation mirrored in x: (x, y, z) → (x, −y, −z)."""


def plausible_hands_mean(rng: np.random.Generator) -> np.ndarray:
    """A relaxed right-hand mean pose (45 axis-angle values): fingers curled about +z, the thumb turned."""
    mean = np.zeros((15, 3))
    for finger in range(4):  # index, middle, pinky, ring: MCP, PIP, DIP flexion like MANO's mean hand
        mean[3 * finger : 3 * finger + 3, 2] = [0.45, 0.75, 0.2]
    mean[12:15] = [[0.6, 0.2, -0.3], [0.1, 0.1, 0.3], [0.0, 0.0, 0.2]]  # thumb
    return (mean + rng.normal(scale=0.05, size=(15, 3))).reshape(45)


def mirror_mano_arrays(arrays: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The left model of a right one: x → −x, faces reversed, mean pose mirrored, shapedirs as is."""
    flip = np.array([-1.0, 1.0, 1.0])
    return {
        **arrays,
        "v_template": arrays["v_template"] * flip,
        "f": arrays["f"][:, ::-1].copy(),
        "hands_mean": (arrays["hands_mean"].reshape(15, 3) * MIRROR_AA).reshape(45),
    }


def synthetic_mano_arrays(seed: int = 0, nverts: int = 778, side: str = "right") -> dict[str, np.ndarray]:
    """The arrays of a synthetic MANO model (all plain numpy; J_regressor dense); left = right mirrored."""
    if side == "left":
        return mirror_mano_arrays(synthetic_mano_arrays(seed, nverts, "right"))
    rng = np.random.default_rng(seed)
    joints = mean_joints(side)
    index = {n: i for i, n in enumerate(NAMES)}
    tips = {}
    if nverts > max(TIP_IDS.values()):
        for finger, vid in TIP_IDS.items():
            j2, j3 = joints[index[f"{finger}2"]], joints[index[f"{finger}3"]]
            tips[vid] = (index[f"{finger}3"], j3 + 1.1 * (j3 - j2) + rng.normal(scale=5e-4, size=3))
    free = [k for k in range(nverts) if k not in tips]
    if len(free) < 16 * 6 + 16 * 4:
        raise ValueError(f"need at least {16 * 10} vertices besides the tips, got {len(free)}")
    vertices = np.zeros((nverts, 3))
    weights = np.zeros((nverts, 16))
    regressor = np.zeros((16, nverts))
    ring = np.vstack([np.eye(3), -np.eye(3)]) * RING_RADIUS
    for j in range(16):
        ids = free[6 * j : 6 * j + 6]
        vertices[ids] = joints[j] + ring
        weights[ids, j] = 1.0
        regressor[j, ids] = rng.dirichlet(np.ones(6))
    children = {j: [c for c in range(16) if PARENTS[c] == j] for j in range(16)}
    tip_of = {index[f"{f}3"]: vid for f, vid in TIP_IDS.items()}
    blob_ids = free[96:]
    for n, k in enumerate(blob_ids):
        j = n % 16
        if j == 0:  # palm: between the wrist and the first joints of the fingers
            w = rng.dirichlet(np.ones(6))
            point = w @ joints[[0, 1, 4, 7, 10, 13]]
        else:
            end = joints[children[j][0]] if children[j] else None
            if end is None:
                end = (
                    tips[tip_of[j]][1] if tip_of[j] in tips else joints[j] + (joints[j] - joints[PARENTS[j]])
                )
            point = joints[j] + rng.uniform(0.1, 0.9) * (end - joints[j])
        vertices[k] = point + rng.normal(scale=BLOB_RADIUS / 2, size=3)
        own = 1.0 if j == 0 else rng.uniform(0.6, 1.0)
        weights[k, j] = own
        if own < 1.0:
            weights[k, PARENTS[j]] = 1.0 - own
    for vid, (j, point) in tips.items():
        vertices[vid] = point
        weights[vid, j] = 1.0
    owner = np.argmax(weights, axis=1)
    faces = []
    for j in range(16):
        ids = np.flatnonzero(owner == j)
        faces.append(ids[ConvexHull(vertices[ids]).simplices])
    components = np.linalg.qr(rng.normal(size=(45, 45)))[0].T
    return {
        "v_template": vertices,
        "shapedirs": rng.normal(scale=2e-3, size=(nverts, 3, 10)),
        "J_regressor": regressor,
        "kintree_table": np.array([[4294967295, *PARENTS[1:]], list(range(16))], dtype=np.int64),
        "weights": weights,
        "f": np.vstack(faces).astype(np.uint32),
        "posedirs": rng.normal(scale=1e-3, size=(nverts, 3, 135)),
        "hands_components": components,
        "hands_mean": plausible_hands_mean(rng),
    }


@contextlib.contextmanager
def _fake_chumpy_and_sparse() -> Iterator[tuple[type, type]]:
    """Register fake ``chumpy.ch.Ch`` and ``scipy.sparse.csc.csc_matrix`` classes while pickling."""
    chumpy = types.ModuleType("chumpy")
    chumpy_ch = types.ModuleType("chumpy.ch")
    csc = types.ModuleType("scipy.sparse.csc")

    class Ch:  # pickled as chumpy.ch.Ch
        pass

    class csc_matrix:  # noqa: N801 - pickled as scipy.sparse.csc.csc_matrix
        pass

    Ch.__module__, Ch.__qualname__ = "chumpy.ch", "Ch"
    csc_matrix.__module__, csc_matrix.__qualname__ = "scipy.sparse.csc", "csc_matrix"
    chumpy_ch.Ch, chumpy.ch, csc.csc_matrix = Ch, chumpy_ch, csc_matrix
    fakes = {"chumpy": chumpy, "chumpy.ch": chumpy_ch, "scipy.sparse.csc": csc}
    saved = {name: sys.modules.get(name) for name in fakes}
    sys.modules.update(fakes)
    try:
        yield Ch, csc_matrix
    finally:
        for name, module in saved.items():
            if module is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = module


def write_synthetic_mano_pkl(
    path: str | Path, *, seed: int = 0, nverts: int = 778, side: str = "right", protocol: int = 2
) -> dict[str, np.ndarray]:
    """Write a synthetic ``MANO_*.pkl`` and return its arrays (J_regressor dense) for the tests' own math."""
    arrays = synthetic_mano_arrays(seed, nverts, side)
    with _fake_chumpy_and_sparse() as (ch_class, csc_class):
        shapedirs = ch_class()
        shapedirs.__dict__.update(
            {"x": arrays["shapedirs"], "_dirty_vars": {"x"}, "_depends_on_deps": {}, "label": None}
        )
        regressor = csc_class()
        dense = arrays["J_regressor"]
        rows, cols = np.nonzero(dense.T)  # column-major order: (col, row) pairs sorted by column
        regressor.__dict__.update(
            {
                "_shape": dense.shape,
                "maxprint": 50,
                "indices": cols.astype(np.int32),
                "indptr": np.searchsorted(rows, np.arange(dense.shape[1] + 1)).astype(np.int32),
                "data": dense.T[rows, cols],
                "format": "csc",
            }
        )
        payload = {
            **{k: v for k, v in arrays.items() if k not in ("shapedirs", "J_regressor")},
            "shapedirs": shapedirs,
            "J_regressor": regressor,
            "J": arrays["J_regressor"] @ arrays["v_template"],
            "bs_style": "lbs",
            "bs_type": "lrotmin",
            "hands_coeffs": np.zeros((3, 45)),
        }
        Path(path).write_bytes(pickle.dumps(payload, protocol=protocol))
    return arrays


WRIST_AT = {"right": (0.18, -0.12, 1.12), "left": (-0.18, -0.12, 1.12)}
"""Where the synthetic hands' wrists hover in ARCTIC's z-up world (metres): beside an object ~1 m up."""


def mano_hand_params(n: int, seed: int = 1, *, scale: float = 0.4, side: str = "right") -> dict:
    """MANO parameters of one hand in ARCTIC's real layout.

    float32 arrays ``rot`` (n, 3), ``pose`` (n, 45, relative to the mean pose), ``trans`` (n, 3) metres,
    ``shape`` (10,), and ``fitting_err`` a plain list of n Python floats. The wrist drifts smoothly (≤ 5 cm,
    ≈ 0.3 m/s) around :data:`WRIST_AT` of ``side``; rotations and poses are random.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 30.0
    phase = rng.uniform(0.0, 2.0 * np.pi, size=3)
    wrist = np.asarray(WRIST_AT[side]) + 0.05 * np.sin(2.0 * np.pi * 1.0 * t[:, None] + phase)
    joint0 = mean_joints(side)[0]
    return {
        "rot": rng.normal(scale=1.0, size=(n, 3)).astype(np.float32),
        "pose": rng.normal(scale=scale, size=(n, 45)).astype(np.float32),
        "trans": (wrist - joint0).astype(np.float32),
        "shape": rng.normal(scale=0.5, size=10).astype(np.float32),
        "fitting_err": [float(x) for x in rng.uniform(0.002, 0.01, size=n)],
    }


def arctic_object_values(
    n: int, seed: int = 0, *, articulation: tuple[float, float] = (0.0, 1.5)
) -> np.ndarray:
    """ARCTIC object rows, float32 (n, 7): articulation rad, axis-angle, translation mm, in a z-up world.

    The object stands about 1 m up and drifts smoothly (≤ 40 mm); its articulation runs between the given
    bounds and its rotation varies smoothly around a random axis-angle.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 30.0
    lo, hi = articulation
    art = lo + (hi - lo) * 0.5 * (1.0 - np.cos(2.0 * np.pi * 0.5 * t))
    rotvec = rng.normal(scale=1.0, size=3) + 0.2 * np.sin(
        2.0 * np.pi * 0.5 * t[:, None] + rng.uniform(0, 6, 3)
    )
    trans = np.array([20.0, -30.0, 1050.0]) + 40.0 * np.sin(
        2.0 * np.pi * 0.5 * t[:, None] + rng.uniform(0, 6, 3)
    )
    return np.column_stack([art, rotvec, trans]).astype(np.float32)


def numpy_mano_fk(arrays, betas, rot, pose, trans):
    """Independent MANO kinematics (smplx's batch_rigid_transform) of one frame with the full pose.

    Returns the rest joints (16, 3), the joints' world rotations (16, 3, 3) and world positions (16, 3).
    """
    joints = arrays["J_regressor"] @ (arrays["v_template"] + arrays["shapedirs"] @ betas)
    rotations = Rotation.from_rotvec(np.vstack([rot, np.reshape(pose, (15, 3))])).as_matrix()
    frames, origins = [rotations[0]], [joints[0]]
    for i in range(1, 16):
        p = PARENTS[i]
        frames.append(frames[p] @ rotations[i])
        origins.append(origins[p] + frames[p] @ (joints[i] - joints[p]))
    return joints, np.array(frames), np.array(origins) + trans


def mujoco_sites(spec, skeleton, trajectory, frame):
    """Every skeleton joint's site position in the MuJoCo hand (mocap root) at a trajectory frame.

    The hand's joints are set to the frame's targets and its mocap root to the root pose; ``mj_kinematics``.
    """
    model = compile_spec(spec)
    data = mujoco.MjData(model)
    for k, name in enumerate(trajectory.dof_names):
        data.qpos[model.joint(name).qposadr[0]] = trajectory.targets[frame, k]
    data.mocap_pos[0] = trajectory.root_pose[frame, :3]
    data.mocap_quat[0] = trajectory.root_pose[frame, 3:]
    mujoco.mj_kinematics(model, data)
    return {j.name: data.site(mj_name(j.name)).xpos.copy() for j in skeleton.joints}


def write_arctic_mano_npy(path: str | Path, right: dict, left: dict) -> None:
    """Write ``<seq>.mano.npy`` exactly as ARCTIC does: ``np.save`` of a dict (pickled object array)."""
    np.save(path, {"right": right, "left": left}, allow_pickle=True)


def write_arctic_object_npy(path: str | Path, values: np.ndarray) -> None:
    """Write ``<seq>.object.npy``: float32 (N, 7) = [articulation, axis-angle (3), translation mm (3)]."""
    np.save(path, np.asarray(values, dtype=np.float32))


def malicious_pickle(marker: Path) -> bytes:
    """A protocol-0 pickle that would run ``os.system('touch <marker>')`` if loaded with pickle.load."""
    return b"cos\nsystem\n(V" + f"touch {marker}".encode() + b"\ntR."


def write_malicious_npy(path: str | Path, marker: Path) -> None:
    """An object-array ``.npy`` whose pickled payload would run ``os.system``."""
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": "|O", "fortran_order": False, "shape": ()})
    Path(path).write_bytes(buffer.getvalue() + malicious_pickle(marker))


GRASP_FLEXION = {1: 1.3, 2: 1.5, 3: 0.7}
"""Flexion (rad) of a finger's MCP (1), PIP (2) and DIP (3) in a closed power grasp (75°, 86°, 40°)."""


def grasp_pose(
    n: int, hands_mean: np.ndarray, side: str, *, closure: float = 1.0, seed: int = 0
) -> np.ndarray:
    """Relative MANO poses (n, 45) of a hand closing from flat (0) to ``closure`` × a power grasp and back.

    Built in right-hand terms (finger flexion about +z, small ab/adduction, seeded noise of 0.05 rad) as the
    full pose, then mirrored for a left hand and made relative to that hand's ``hands_mean``.
    """
    rng = np.random.default_rng(seed)
    c = closure * 0.5 * (1.0 - np.cos(2.0 * np.pi * np.arange(n) / max(n - 1, 1)))
    full = np.zeros((n, 15, 3))
    for j in range(12):  # index, middle, pinky, ring × (1, 2, 3)
        full[:, j, 2] = c * GRASP_FLEXION[j % 3 + 1]
        full[:, j, 1] = rng.uniform(-0.1, 0.1)
    right_mean = hands_mean.reshape(15, 3) * (MIRROR_AA if side == "left" else 1.0)
    full[:, 12:] = right_mean[12:] + c[:, None, None] * np.array([0.3, 0.2, 0.4])  # thumb opposes
    full += rng.normal(scale=0.05, size=full.shape)
    if side == "left":
        full = full * MIRROR_AA
    return (full.reshape(n, 45) - hands_mean).astype(np.float32)
