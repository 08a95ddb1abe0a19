"""The architecture is enforced: the import-linter contracts in pyproject.toml hold, and a violation fails.

The contracts (a layers contract: cli → report/export → envs/runner → viz → trials → sim → builders → io →
glove → datatypes → base; the report reads records only) are checked on the source tree. The second test
copies the package, adds one upward import to a data-type module and shows that ``lint-imports`` refuses
it, naming the offending import; the inner contracts of the simulation layer (replay on top, then the
placement search, the stability tests, the replay core's parts, the specs and the compiled scene) and of
the readers (dataset families independent of each other) are shown to refuse a violation the same way.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("importlinter", reason='import-linter checks the layers: pip install ".[test]"')


def _lint_imports(root: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(root)}
    code = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"
    return subprocess.run(
        [sys.executable, "-c", code, "--no-cache", str(root / "pyproject.toml")],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_import_contracts_are_kept():
    run = _lint_imports(ROOT)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "Contracts: 6 kept, 0 broken." in run.stdout


def _package_copy(tmp_path: Path) -> Path:
    def python_only(folder: str, names: list[str]) -> list[str]:  # lint-imports reads Python files only
        return [n for n in names if n == "__pycache__" or not (n.endswith(".py") or Path(folder, n).is_dir())]

    shutil.copytree(ROOT / "handsim", tmp_path / "handsim", ignore=python_only)
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    return tmp_path


def _add_lazy_import(module: Path, imported: str) -> None:
    module.write_text(module.read_text() + f"\n\ndef _added():\n    import {imported}  # noqa: F401\n")


def test_lint_imports_fails_when_a_data_type_imports_the_cli(tmp_path):
    root = _package_copy(tmp_path)
    _add_lazy_import(root / "handsim" / "datatypes" / "skeleton.py", "handsim.cli")
    run = _lint_imports(root)
    assert run.returncode == 1
    assert "handsim.datatypes is not allowed to import handsim.cli:" in run.stdout
    assert "handsim.datatypes.skeleton -> handsim.cli" in run.stdout


def test_lint_imports_fails_on_a_cycle_within_a_layer(tmp_path):
    root = _package_copy(tmp_path)  # object_model imports mesh; mesh importing object_model closes a cycle
    _add_lazy_import(root / "handsim" / "datatypes" / "mesh.py", "handsim.datatypes.object_model")
    run = _lint_imports(root)
    assert run.returncode == 1
    assert "Contracts: 5 kept, 1 broken." in run.stdout
    assert (
        "No cycles are allowed in handsim.datatypes." in run.stdout
        and "- .object_model -> .mesh" in run.stdout
    )


def test_lint_imports_fails_when_a_stability_test_imports_the_placement_search(tmp_path):
    root = _package_copy(tmp_path)
    _add_lazy_import(root / "handsim" / "sim" / "stability" / "gravity.py", "handsim.sim.placement.search")
    run = _lint_imports(root)
    assert run.returncode == 1
    assert "handsim.sim.stability is not allowed to import handsim.sim.placement:" in run.stdout


def test_lint_imports_fails_when_a_spec_imports_the_replay_core(tmp_path):
    root = _package_copy(tmp_path)
    _add_lazy_import(root / "handsim" / "sim" / "specs.py", "handsim.sim.metrics")
    run = _lint_imports(root)
    assert run.returncode == 1
    assert "handsim.sim.specs is not allowed to import handsim.sim.metrics:" in run.stdout


def test_lint_imports_fails_when_one_dataset_family_reads_another(tmp_path):
    root = _package_copy(tmp_path)
    _add_lazy_import(root / "handsim" / "io" / "tzionas" / "motion.py", "handsim.io.graspdb.rows")
    run = _lint_imports(root)
    assert run.returncode == 1
    assert "handsim.io.tzionas is not allowed to import handsim.io.graspdb:" in run.stdout
