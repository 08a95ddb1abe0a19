"""The training scripts write to a fresh folder by default and never into a run's results unasked."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from tests.helpers import load_script


def _script():
    return load_script("train_residual")


def _parsed(module, argv: list[str]) -> tuple[argparse.ArgumentParser, argparse.Namespace]:
    parser = argparse.ArgumentParser(prog="train_residual.py")
    module.add_output_options(parser, "residual")
    return parser, parser.parse_args(argv)


def test_the_default_output_is_a_fresh_folder_under_runs(tmp_path, monkeypatch) -> None:
    module = _script()
    monkeypatch.chdir(tmp_path)
    parser, args = _parsed(module, [])
    first = module.output_folder(parser, args, "residual")
    assert first.parent == Path("runs") and first.name.startswith("residual-")
    assert not first.exists()  # made when the run writes, not before (a missing extra leaves nothing)
    first.mkdir(parents=True)
    second = module.output_folder(parser, args, "residual")
    assert second != first and not second.exists()


def test_an_out_folder_holding_files_is_refused_unless_overwrite(tmp_path, capsys) -> None:
    module = _script()
    published = tmp_path / "rl"
    published.mkdir()
    (published / "evaluation.json").write_text("{}")
    parser, args = _parsed(module, ["--out", str(published)])
    with pytest.raises(SystemExit) as exit_:
        module.output_folder(parser, args, "residual")
    assert exit_.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"train_residual.py: error: argument --out: {published} holds files already (a run's results?): "
        "give a new folder, or add --overwrite to replace them"
    )
    parser, args = _parsed(module, ["--out", str(published), "--overwrite"])
    assert module.output_folder(parser, args, "residual") == published
    parser, args = _parsed(module, ["--out", str(tmp_path / "empty")])
    (tmp_path / "empty").mkdir()
    assert module.output_folder(parser, args, "residual") == tmp_path / "empty"


def test_torch_threads_must_be_a_whole_number_of_at_least_one(capsys) -> None:
    with pytest.raises(SystemExit) as exit_:
        _script().main(["--torch-threads", "0"])
    assert exit_.value.code == 2
    assert (
        capsys.readouterr()
        .err.splitlines()[-1]
        .endswith(": error: argument --torch-threads: expected a whole number ≥ 1, got 0")
    )
