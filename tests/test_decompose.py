"""Tests of handsim.builders.decompose: CoACD in a child process, timeout, crash handling, disk cache.

CoACD runs are few and small (a 128-vertex annulus with coarse settings, about 1 s each); the module
fixture's result is reused by most tests.
"""

from __future__ import annotations

import dataclasses
import re
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

from handsim.builders import coacd_process, hull_cache
from handsim.builders import decompose as dec
from handsim.builders.decompose import decompose
from handsim.builders.decomposition_types import (
    ConvexHull,
    Decomposition,
    DecompositionError,
    DecompositionParams,
)
from handsim.builders.hull_cache import cache_key
from handsim.cache import CorruptEntryError, array_checksum, default_cache_dir
from handsim.datatypes.mesh import Mesh, validate_mesh
from handsim.errors import MeshError

R_MIN, R_MAX, HEIGHT = 0.02, 0.04, 0.02
PARAMS = DecompositionParams(resolution=500, preprocess_resolution=30, mcts_iterations=60)


@pytest.fixture(scope="module")
def annulus() -> Mesh:
    t = trimesh.creation.annulus(r_min=R_MIN, r_max=R_MAX, height=HEIGHT)
    return validate_mesh(t.vertices, t.faces, source="annulus")


@pytest.fixture(scope="module")
def decomposed(annulus: Mesh, tmp_path_factory: pytest.TempPathFactory) -> tuple[Decomposition, Path]:
    """The annulus decomposed once with a fresh cache (which now holds its entry)."""
    cache = tmp_path_factory.mktemp("cache")
    return decompose(annulus, PARAMS, cache_dir=cache), cache


# Workers that fail on purpose, started by decompose() in place of _coacd_worker.py (same command line:
# IN.npz OUT.npz). They load the real worker by path for its output format and its core-dump setting.
_FAULTY_WORKER_HEAD = f"""
import importlib.util, os, sys
spec = importlib.util.spec_from_file_location("_coacd_worker", {str(coacd_process._WORKER)!r})
real = importlib.util.module_from_spec(spec)
spec.loader.exec_module(real)
out_path = sys.argv[2]
"""
FAULTY_WORKERS = {
    "abort": 'real._no_core_dumps()\nprint("deliberate abort by the faulty worker", flush=True)\nos.abort()',
    "exit 2": 'print("the faulty worker exits with status 2", file=sys.stderr)\nsys.exit(2)\n',
    "empty": "real._save(out_path, real._pack([], 0.0))\n",
    "garbage": 'open(out_path, "wb").write(b"this is not an npz file")\n',
}


@pytest.fixture
def faulty_worker(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch):
    """Make decompose() start a worker that fails in the named way (a key of FAULTY_WORKERS)."""

    def use(fault: str) -> None:
        script = tmp_path_factory.mktemp("worker") / "faulty_worker.py"
        script.write_text(_FAULTY_WORKER_HEAD + FAULTY_WORKERS[fault])
        monkeypatch.setattr(coacd_process, "_WORKER", script)

    return use


def entry_path(cache: Path, key: str) -> Path:
    return cache / "coacd" / key[:2] / f"{key}.npz"


def files_under(path: Path) -> list[Path]:
    return sorted(p for p in path.rglob("*") if p.is_file())


def assert_same_hulls(a: Decomposition, b: Decomposition) -> None:
    assert len(a.hulls) == len(b.hulls)
    for ha, hb in zip(a.hulls, b.hulls, strict=True):
        assert ha.vertices.dtype == hb.vertices.dtype == np.float64
        assert ha.faces.dtype == hb.faces.dtype == np.int64
        assert ha.vertices.tobytes() == hb.vertices.tobytes()
        assert ha.faces.tobytes() == hb.faces.tobytes()


# ------------------------------------------------------------------------------------------ convex mesh


def test_decompose_skips_coacd_for_convex_mesh(tmp_path: Path) -> None:
    box = trimesh.creation.box((0.1, 0.2, 0.3))
    mesh = validate_mesh(box.vertices, box.faces, source="box")
    result = decompose(mesh, PARAMS, cache_dir=tmp_path)
    assert result.skipped == "mesh is convex"
    assert len(result.hulls) == 1
    assert result.hulls[0].vertices.shape == (8, 3)
    assert result.hulls[0].faces.shape == (12, 3)
    assert result.hulls[0].volume == pytest.approx(0.1 * 0.2 * 0.3, rel=1e-12)
    assert (result.from_cache, result.seconds, result.coacd_seconds, result.notes) == (False, 0.0, 0.0, ())
    assert result.key == cache_key(mesh, PARAMS)
    assert files_under(tmp_path) == []


def test_decompose_skips_coacd_for_convex_sphere() -> None:
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.05)
    mesh = validate_mesh(sphere.vertices, sphere.faces, source="sphere")
    result = decompose(mesh, PARAMS, use_cache=False)
    assert result.skipped == "mesh is convex"
    assert len(result.hulls[0].vertices) == len(mesh.vertices)


# ---------------------------------------------------------------------------------------- concave mesh


def test_decompose_splits_concave_mesh_into_hulls_that_cover_it(
    annulus: Mesh, decomposed: tuple[Decomposition, Path]
) -> None:
    result, _ = decomposed
    assert result.skipped == ""
    assert result.from_cache is False
    assert result.notes == ()
    assert 1 < len(result.hulls) <= PARAMS.max_convex_hull
    assert result.seconds > 0
    assert result.coacd_seconds == result.seconds
    assert sum(h.volume for h in result.hulls) >= 0.95 * annulus.volume
    tol = 0.003  # every hull vertex within 3 mm of the annulus, or inside it
    for hull in result.hulls:
        r = np.linalg.norm(hull.vertices[:, :2], axis=1)
        assert np.all(r >= R_MIN - tol)
        assert np.all(r <= R_MAX + tol)
        assert np.all(np.abs(hull.vertices[:, 2]) <= HEIGHT / 2 + tol)


def test_decompose_returns_valid_convex_hulls(decomposed: tuple[Decomposition, Path]) -> None:
    result, _ = decomposed
    for hull in result.hulls:
        assert hull.vertices.dtype == np.float64
        assert hull.faces.dtype == np.int64
        assert 4 <= len(hull.vertices) <= PARAMS.max_ch_vertex
        assert hull.faces.min() == 0
        assert hull.faces.max() == len(hull.vertices) - 1
        t = trimesh.Trimesh(hull.vertices, hull.faces, process=False)
        assert t.is_watertight
        assert t.is_convex
        assert t.volume > 0


def test_decompose_hulls_compile_as_mujoco_meshes(decomposed: tuple[Decomposition, Path]) -> None:
    result, _ = decomposed
    spec = mujoco.MjSpec()
    for i, hull in enumerate(result.hulls):
        mesh = spec.add_mesh()
        mesh.name = f"hull_{i}"
        mesh.uservert = hull.vertices.ravel().tolist()
        mesh.userface = hull.faces.ravel().tolist()
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"hull_{i}")
    model = spec.compile()
    assert model.nmesh == len(result.hulls)
    assert model.mesh_vertnum.tolist() == [len(h.vertices) for h in result.hulls]


def test_decompose_is_deterministic_and_use_cache_false_neither_reads_nor_writes(
    annulus: Mesh, decomposed: tuple[Decomposition, Path]
) -> None:
    first, cache = decomposed
    before = {p: p.stat().st_mtime_ns for p in files_under(cache)}
    second = decompose(annulus, PARAMS, cache_dir=cache, use_cache=False)
    assert second.from_cache is False
    assert second.seconds > 0
    assert_same_hulls(first, second)
    assert {p: p.stat().st_mtime_ns for p in files_under(cache)} == before


# ----------------------------------------------------------------------------------------------- cache


def test_decompose_reads_second_call_from_cache(
    annulus: Mesh, decomposed: tuple[Decomposition, Path]
) -> None:
    first, cache = decomposed
    assert files_under(cache) == [entry_path(cache, first.key)]
    again = decompose(annulus, PARAMS, cache_dir=cache)  # its time: benchmarks/io_and_cache.py
    assert again.from_cache is True
    assert again.key == first.key
    assert again.seconds == 0.0
    assert again.coacd_seconds == first.seconds
    assert again.notes == ()
    assert_same_hulls(first, again)


def test_a_cache_hit_computes_no_hull(
    annulus: Mesh, decomposed: tuple[Decomposition, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    # The cache is read before the convexity test (only concave meshes are ever cached), so a warm build
    # needs no qhull and imports neither trimesh nor SciPy.
    first, cache = decomposed

    def no_hull(points: np.ndarray) -> None:
        raise AssertionError("a cache hit computed a hull")

    monkeypatch.setattr(dec, "_hull_of", no_hull)
    again = decompose(annulus, PARAMS, cache_dir=cache)
    assert again.from_cache is True
    assert_same_hulls(first, again)


def test_decompose_uses_default_cache_dir_from_environment(
    annulus: Mesh, decomposed: tuple[Decomposition, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    _, cache = decomposed
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(cache))
    assert decompose(annulus, PARAMS).from_cache is True


def test_cache_key_changes_with_params_and_mesh_but_not_timeout(annulus: Mesh) -> None:
    key = cache_key(annulus, PARAMS)
    assert re.fullmatch(r"[0-9a-f]{64}", key)
    assert cache_key(annulus, dataclasses.replace(PARAMS)) == key
    assert cache_key(annulus, dataclasses.replace(PARAMS, timeout_s=1.0)) == key
    for change in ({"threshold": 0.1}, {"seed": 1}, {"max_convex_hull": -1}, {"preprocess_mode": "on"}):
        assert cache_key(annulus, dataclasses.replace(PARAMS, **change)) != key, change
    moved = Mesh(annulus.vertices + np.array([0.0, 0.0, 1e-9]), annulus.faces, source=annulus.source)
    assert cache_key(moved, PARAMS) != key
    flipped = Mesh(annulus.vertices, annulus.faces[:, ::-1], source=annulus.source)
    assert cache_key(flipped, PARAMS) != key
    renamed = Mesh(annulus.vertices, annulus.faces, source="another name")
    assert cache_key(renamed, PARAMS) == key


def test_decompose_rebuilds_corrupt_cache_entry_with_note(
    annulus: Mesh, decomposed: tuple[Decomposition, Path], tmp_path: Path
) -> None:
    first, _ = decomposed
    entry = entry_path(tmp_path, first.key)
    entry.parent.mkdir(parents=True)
    entry.write_bytes(b"\x00garbage, not an npz file\xff")
    rebuilt = decompose(annulus, PARAMS, cache_dir=tmp_path)
    assert rebuilt.from_cache is False
    assert len(rebuilt.notes) == 1
    assert re.fullmatch(
        rf"cache entry {re.escape(str(entry))} was corrupt \(unreadable: .+\) and was rebuilt",
        rebuilt.notes[0],
    )
    assert_same_hulls(first, rebuilt)
    assert files_under(tmp_path) == [entry]
    again = decompose(annulus, PARAMS, cache_dir=tmp_path)
    assert again.from_cache is True
    assert again.notes == ()
    assert_same_hulls(first, again)


def _rewrite(entry: Path, target: Path, change: str) -> None:
    """Copy a valid entry to ``target`` with one kind of damage."""
    with np.load(entry, allow_pickle=False) as data:
        arrays = {k: np.asarray(data[k]) for k in data.files}
    if change == "truncated":
        target.write_bytes(entry.read_bytes()[: entry.stat().st_size // 2])
        return
    if change == "checksum":
        arrays["vertices"] = arrays["vertices"] + 1e-3
    else:
        if change == "missing":
            del arrays["faces"]
        elif change == "shape":
            arrays["vertices"] = arrays["vertices"][:, :2].copy()
        elif change == "index":
            arrays["faces"] = arrays["faces"].copy()
            arrays["faces"][0, 0] = 10_000
        del arrays["checksum"]
        arrays["checksum"] = np.array(array_checksum(arrays))
    with open(target, "wb") as f:
        np.savez(f, **arrays)


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ("truncated", r"unreadable: .+"),
        ("missing", r"missing arrays faces"),
        ("checksum", r"checksum mismatch"),
        ("shape", r"vertices must be floats of shape \(N, 3\), got float64 \(\d+, 2\)"),
        ("index", r"hull 0 has a face index outside 0\.\.\d+"),
    ],
)
def test_read_entry_rejects_damaged_cache_entry(
    decomposed: tuple[Decomposition, Path], tmp_path: Path, change: str, reason: str
) -> None:
    first, cache = decomposed
    damaged = tmp_path / "entry.npz"
    _rewrite(entry_path(cache, first.key), damaged, change)
    with pytest.raises(CorruptEntryError, match=rf"^{reason}$"):
        hull_cache.read_entry(damaged)


def test_write_entry_is_atomic_and_round_trips(
    decomposed: tuple[Decomposition, Path], tmp_path: Path
) -> None:
    first, _ = decomposed
    path = tmp_path / "ab" / "entry.npz"
    hull_cache.write_entry(path, first.hulls, 1.25, ("a note",))
    assert files_under(tmp_path) == [path]  # no temporary file left behind
    hulls, seconds, notes = hull_cache.read_entry(path)
    assert (seconds, notes) == (1.25, ("a note",))
    assert_same_hulls(first, dataclasses.replace(first, hulls=hulls))


def test_default_cache_dir_honours_handsim_cache_dir(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path / "mine"))
    assert default_cache_dir() == tmp_path / "mine"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="XDG applies on Linux")
def test_default_cache_dir_follows_xdg_on_linux(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("HANDSIM_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_cache_dir() == tmp_path / "handsim"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert default_cache_dir() == Path.home() / ".cache" / "handsim"


# ---------------------------------------------------------------------------------------------- errors


def test_decompose_raises_exact_error_on_timeout_and_caches_nothing(annulus: Mesh, tmp_path: Path) -> None:
    params = dataclasses.replace(PARAMS, timeout_s=0.01)  # how soon it returns: benchmarks/io_and_cache.py
    with pytest.raises(
        DecompositionError,
        match=r"^annulus: CoACD did not finish within 0\.01 s \(threshold 0\.05, max 16 hulls\); "
        r"raise the timeout or the threshold$",
    ):
        decompose(annulus, params, cache_dir=tmp_path)
    assert files_under(tmp_path) == []


def test_timeout_message_says_no_hull_limit(annulus: Mesh) -> None:
    params = dataclasses.replace(PARAMS, timeout_s=0.01, max_convex_hull=-1, threshold=0.2)
    with pytest.raises(DecompositionError, match=r"\(threshold 0\.2, no hull limit\)"):
        decompose(annulus, params, use_cache=False)


@pytest.mark.skipif(sys.platform == "win32", reason="abort is a signal on POSIX only")
def test_decompose_raises_error_naming_mesh_if_coacd_crashes(
    annulus: Mesh, tmp_path: Path, faulty_worker
) -> None:
    faulty_worker("abort")
    with pytest.raises(
        DecompositionError,
        match=r"(?s)^annulus: the CoACD worker was killed by signal 6 \(SIGABRT\); "
        r"last lines of its output:\n"
        r".*deliberate abort by the faulty worker.*$",
    ) as info:
        decompose(annulus, PARAMS, cache_dir=tmp_path)
    assert isinstance(info.value, MeshError)
    assert files_under(tmp_path) == []


def test_decompose_raises_error_if_worker_exits_with_error(annulus: Mesh, faulty_worker) -> None:
    faulty_worker("exit 2")
    with pytest.raises(
        DecompositionError,
        match=r"^annulus: the CoACD worker exited with status 2; last lines of its output:\n"
        r"the faulty worker exits with status 2$",
    ):
        decompose(annulus, PARAMS, use_cache=False)


def test_decompose_raises_error_if_coacd_returns_no_hulls(
    annulus: Mesh, faulty_worker, capsys: pytest.CaptureFixture[str]
) -> None:
    faulty_worker("empty")
    with pytest.raises(DecompositionError, match=r"^annulus: CoACD returned no hulls$"):
        decompose(annulus, PARAMS, use_cache=False)
    assert capsys.readouterr().err == ""  # quiet unless asked for progress


def test_decompose_raises_error_if_worker_output_is_not_npz(annulus: Mesh, faulty_worker) -> None:
    faulty_worker("garbage")
    with pytest.raises(DecompositionError, match=r"^annulus: the CoACD worker wrote invalid output \(.+\)$"):
        decompose(annulus, PARAMS, use_cache=False)


CHATTY_WORKER = (
    "import time\n"
    "for k in range(2000):  # CoACD's own progress: carriage returns, on both streams\n"
    "    print(f'\\r[CoACD] {k / 20:.1f} %', end='', file=sys.stdout if k % 2 else sys.stderr)\n"
    "time.sleep(0.3)  # the parent polls a few times meanwhile\n"
    "cube = real.np.array([[x, y, z] for x in (0, 0.01) for y in (0, 0.01) for z in (0, 0.01)])\n"
    "faces = real.np.array([[0, 1, 2], [1, 3, 2], [4, 6, 5], [5, 6, 7], [0, 4, 1], [1, 4, 5],\n"
    "                       [2, 3, 6], [3, 7, 6], [0, 2, 4], [2, 6, 4], [1, 5, 3], [3, 5, 7]])\n"
    "real._save(out_path, real._pack([(cube, faces)], 0.3))\n"
)
"""A worker that floods its output with CoACD-like progress lines, then returns one cube."""


@pytest.fixture
def chatty_worker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    script = tmp_path / "chatty_worker.py"
    script.write_text(_FAULTY_WORKER_HEAD + CHATTY_WORKER)
    monkeypatch.setattr(coacd_process, "_WORKER", script)


def test_decompose_progress_in_a_log_is_two_plain_lines_and_none_of_coacds_own_output(
    annulus: Mesh, chatty_worker, capsys: pytest.CaptureFixture[str]
) -> None:
    decompose(annulus, PARAMS, use_cache=False, progress=True)  # stderr captured: not a terminal
    captured = capsys.readouterr()
    assert "\r" not in captured.err and captured.out == ""
    lines = captured.err.splitlines()
    assert lines[0] == f"CoACD annulus: running, timeout {PARAMS.timeout_s:g} s"
    assert re.fullmatch(r"CoACD annulus: done after \d+\.\d s", lines[1]) and len(lines) == 2


def test_decompose_progress_on_a_terminal_is_a_bar_counting_the_time(
    annulus: Mesh, chatty_worker, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("handsim.progress.is_terminal", lambda: True)
    decompose(annulus, PARAMS, use_cache=False, progress=True)
    err = capsys.readouterr().err
    assert "\rCoACD annulus: 00:0" in err and err.rstrip().endswith(", done")
    assert "[CoACD]" not in err and "running, timeout" in err and "done after" not in err


def test_decompose_shows_no_progress_unless_asked(
    annulus: Mesh, chatty_worker, capsys: pytest.CaptureFixture[str]
) -> None:
    decompose(annulus, PARAMS, use_cache=False)
    assert capsys.readouterr() == ("", "")


def test_usable_hulls_drops_flat_hull_with_note() -> None:
    cube = trimesh.creation.box((0.01, 0.01, 0.01))
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float) * 0.01
    raw = [(np.asarray(cube.vertices), np.asarray(cube.faces)), (flat, np.array([[0, 1, 2], [1, 3, 2]]))]
    hulls, notes = dec._usable_hulls(raw, "cube")
    assert len(hulls) == 1
    assert notes == ["dropped CoACD hull 1 of 2: flat or degenerate (4 vertices)"]


def test_usable_hulls_raises_error_if_every_hull_is_flat() -> None:
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    line = np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]], dtype=float)
    tri = np.array([[0, 1, 2]])
    with pytest.raises(
        DecompositionError, match=r"^plate: all 2 hulls returned by CoACD are flat or degenerate$"
    ):
        dec._usable_hulls([(flat, tri), (line, tri)], "plate")


# ---------------------------------------------------------------------------------------------- params


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"threshold": 0.001}, r"threshold must be in \[0\.01, 1\], got 0\.001"),
        ({"threshold": 1.5}, r"threshold must be in \[0\.01, 1\], got 1\.5"),
        ({"threshold": float("nan")}, r"threshold must be a finite number, got nan"),
        ({"max_convex_hull": 0}, r"max_convex_hull must be -1 \(no limit\) or at least 1, got 0"),
        ({"max_convex_hull": 2.5}, r"max_convex_hull must be an integer, got 2\.5"),
        ({"preprocess_mode": "yes"}, r"preprocess_mode must be one of 'auto', 'on', 'off', got 'yes'"),
        ({"resolution": 0}, r"resolution must be at least 1, got 0"),
        ({"mcts_iterations": True}, r"mcts_iterations must be an integer, got True"),
        ({"max_ch_vertex": 3}, r"max_ch_vertex must be at least 4 \(a hull needs 4 vertices\), got 3"),
        ({"seed": -1}, r"seed must be in \[0, 2\*\*32 - 1\], got -1"),
        ({"timeout_s": 0}, r"timeout_s must be positive, got 0\.0"),
    ],
)
def test_params_raise_value_error_if_invalid(change: dict, message: str) -> None:
    with pytest.raises(ValueError, match=rf"^{message}$"):
        DecompositionParams(**change)


def test_params_normalise_numpy_numbers() -> None:
    params = DecompositionParams(threshold=np.float32(0.5), seed=np.int64(3))
    assert type(params.threshold) is float
    assert type(params.seed) is int
    assert cache_key(_tetra(), params) == cache_key(_tetra(), DecompositionParams(threshold=0.5, seed=3))


def _tetra() -> Mesh:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return validate_mesh(v, f, source="tetra")


def test_convex_hull_volume_is_in_cubic_metres() -> None:
    t = trimesh.creation.box((0.1, 0.1, 0.1))
    assert ConvexHull(np.asarray(t.vertices), np.asarray(t.faces)).volume == pytest.approx(1e-3)
