"""Children that end with their parent (handsim.lifeline): each mechanism alone, under kill -9."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from handsim import lifeline
from tests.processes import child_env, linux_only, reaped, wait_for

SENTINEL_PARENT = """
import multiprocessing, multiprocessing.connection, time
from handsim import lifeline

def child():
    parent = multiprocessing.parent_process()
    lifeline.watch(lambda: multiprocessing.connection.wait([parent.sentinel]))  # no prctl: the portable one
    time.sleep(3600)

if __name__ == "__main__":
    process = multiprocessing.get_context("spawn").Process(target=child)
    process.start()
    print(process.pid, flush=True)
    time.sleep(3600)
"""

STDIN_PARENT = """
import subprocess, sys, time
child = subprocess.Popen([sys.executable, "-c", {child!r}], stdin=subprocess.PIPE)
print(child.pid, flush=True)
time.sleep(3600)
"""
STDIN_CHILD = """
import os, time
from handsim import lifeline
def read_to_end():
    while os.read(0, 4096):
        pass
lifeline.watch(read_to_end)
time.sleep(3600)
"""

PDEATHSIG_PARENT = """
import os, subprocess, sys, time
child = subprocess.Popen([sys.executable, "-c", {child!r}, str(os.getpid())], stdin=subprocess.DEVNULL)
print(child.pid, flush=True)
time.sleep(3600)
"""
PDEATHSIG_CHILD = """
import sys, time
from handsim import lifeline
assert lifeline.die_with_parent(int(sys.argv[1]))  # exits at once if the parent died before
time.sleep(3600)
"""


def _child_dies_with_parent(tmp_path, script: str) -> None:
    path = tmp_path / "parent.py"
    path.write_text(textwrap.dedent(script))
    parent = subprocess.Popen([sys.executable, str(path)], stdout=subprocess.PIPE, env=child_env())
    with reaped(parent) as children:
        pid = int(parent.stdout.readline())
        children.add({pid})
        assert children.alive() == [pid]
        parent.kill()
        parent.wait(timeout=30)
        wait_for(lambda: not children.alive(), 60, "the child outlived its parent")


@linux_only
def test_a_child_watching_its_parents_sentinel_ends_with_the_parent(tmp_path):
    _child_dies_with_parent(tmp_path, SENTINEL_PARENT)


@linux_only
def test_a_child_reading_its_stdin_pipe_ends_with_the_parent(tmp_path):
    _child_dies_with_parent(tmp_path, STDIN_PARENT.format(child=STDIN_CHILD))


@linux_only
def test_a_child_with_the_parent_death_signal_ends_with_the_parent(tmp_path):
    _child_dies_with_parent(tmp_path, PDEATHSIG_PARENT.format(child=PDEATHSIG_CHILD))


def test_die_with_parent_is_a_no_op_off_linux(monkeypatch):
    monkeypatch.setattr(lifeline.sys, "platform", "darwin")
    assert lifeline.die_with_parent() is False
