"""Tests of handsim.builders.mesh_cache: the catalogue's generated meshes on disk."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from handsim.builders import graspdb_objects, mesh_cache
from handsim.builders.mesh_cache import entry_path, generated_mesh, mesh_key, read_entry, write_entry
from handsim.cache import CorruptEntryError, array_checksum


def _generate_mug():
    return graspdb_objects._generate("mug")


@pytest.fixture(scope="module")
def mug():
    return _generate_mug()


def _same(a, b) -> None:
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)
    assert a.vertices.dtype == b.vertices.dtype and a.faces.dtype == b.faces.dtype
    assert (a.source, a.watertight, a.notes) == (b.source, b.watertight, b.notes)


def test_a_generated_mesh_is_written_once_and_read_back_bitwise(mug, tmp_path: Path) -> None:
    calls = []

    def generate():
        calls.append(1)
        return mug

    first = generated_mesh("mug", generate, cache_dir=tmp_path)
    second = generated_mesh("mug", generate, cache_dir=tmp_path)
    assert len(calls) == 1
    assert first is mug
    _same(second, mug)
    assert [p.relative_to(tmp_path) for p in tmp_path.rglob("*.npz")] == [
        entry_path(tmp_path, mesh_key("mug")).relative_to(tmp_path)
    ]


def test_the_key_names_the_object_and_the_code(monkeypatch: pytest.MonkeyPatch) -> None:
    assert mesh_key("mug") != mesh_key("bowl")
    assert mesh_key("mug") == mesh_key("mug")
    before = mesh_key("mug")
    monkeypatch.setattr(mesh_cache, "source_fingerprint", lambda: "0" * 64)
    assert mesh_key("mug") != before  # any edit of handsim's source gives new keys


def test_a_corrupt_entry_is_regenerated_replaced_and_logged(
    mug, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = entry_path(tmp_path, mesh_key("mug"))
    write_entry(path, mug)
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with caplog.at_level(logging.WARNING, logger="handsim.builders.mesh_cache"):
        mesh = generated_mesh("mug", _generate_mug, cache_dir=tmp_path)
    _same(mesh, mug)
    assert "is corrupt" in caplog.text and str(path) in caplog.text
    _same(read_entry(path), mug)  # replaced by a good entry


@pytest.mark.parametrize(
    "damage, message",
    [
        (lambda a: a.pop("faces"), "missing arrays faces"),
        (lambda a: a.update(format=np.array(99, dtype=np.int64)), "format"),
        (lambda a: a.update(faces=a["faces"] + 10**6), "not a triangle mesh"),
    ],
    ids=["missing", "format", "indices"],
)
def test_read_entry_rejects_damaged_entries(mug, tmp_path: Path, damage, message: str) -> None:
    # the checksum is recomputed after the damage, so each check is reached on its own
    path = tmp_path / "entry.npz"
    write_entry(path, mug)
    with np.load(path) as data:
        arrays = {k: np.asarray(data[k]) for k in data.files if k != "checksum"}
    damage(arrays)
    arrays["checksum"] = np.array(array_checksum(arrays))
    np.savez(path, **arrays)
    with pytest.raises(CorruptEntryError, match=message):
        read_entry(path)


def test_a_cache_that_cannot_be_written_still_gives_the_mesh(
    mug, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with caplog.at_level(logging.WARNING, logger="handsim.builders.mesh_cache"):
        mesh = generated_mesh("mug", lambda: mug, cache_dir=blocker)
    assert mesh is mug
    assert "could not write mesh cache entry" in caplog.text


def test_the_catalogue_mesh_from_the_cache_is_the_generated_one(
    mug, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HANDSIM_CACHE_DIR", str(tmp_path))
    graspdb_objects.clear_mesh_cache()
    try:
        graspdb_objects.graspdb_object("mug").mesh()  # generated and written
        graspdb_objects.clear_mesh_cache()
        _same(graspdb_objects.graspdb_object("mug").mesh(), mug)  # read back
        assert len(list(tmp_path.rglob("*.npz"))) == 1
    finally:
        graspdb_objects.clear_mesh_cache()
