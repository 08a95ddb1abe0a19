"""OpenGL backend choice (handsim.viz.headless): made when a renderer is made, never on ``import handsim``."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import mujoco
import pytest

from handsim.errors import RenderError
from handsim.viz import headless

ROOT = Path(__file__).resolve().parents[1]
SPHERE = (
    "<mujoco><worldbody><light pos='0 0 1'/>"
    "<geom type='sphere' size='.1' rgba='1 0 0 1'/></worldbody></mujoco>"
)


def _fresh_python(code: str, *args: str) -> subprocess.CompletedProcess:
    """Run ``code`` (with ``args`` in ``sys.argv[1:]``) in a new interpreter without display or MUJOCO_GL."""
    drop = ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL", "PYOPENGL_PLATFORM")
    environ = {k: v for k, v in os.environ.items() if k not in drop}
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code), *args],
        cwd=ROOT,
        env=environ,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_import_handsim_sets_no_environment_variable():
    # gymnasium (imported to register the environments) sets PYGAME_HIDE_SUPPORT_PROMPT itself: import it
    # first, so that only what handsim would add shows.
    done = _fresh_python(
        """
        import os, gymnasium
        before = dict(os.environ)
        import handsim, handsim.envs, handsim.cli, handsim.viz.headless
        after = dict(os.environ)
        print(sorted(set(after.items()) ^ set(before.items())), "MUJOCO_GL" in after)
        """
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[] False"


@pytest.mark.parametrize(
    ("platform", "display", "mujoco_gl", "mujoco_choice", "expected"),
    [
        ("linux", "", "", "glfw", "egl"),  # nothing chosen, no display: EGL for handsim's renderers
        ("linux", ":0", "", "glfw", "glfw"),  # a display: MuJoCo's default
        ("linux", "", "osmesa", "osmesa", "osmesa"),  # the user's choice
        ("linux", "", "egl", "egl", "egl"),
        ("linux", "", "glfw", "glfw", None),  # the user's GLFW without a display: refused, not tried
        ("linux", "", "osmesa", "glfw", "osmesa"),  # MUJOCO_GL set after mujoco was imported (GLFW)
        ("linux", "", "enable", "glfw", None),  # GLFW by another name
        ("darwin", "", "", "cgl", "cgl"),  # not Linux: MuJoCo's choice
    ],
)
def test_offscreen_backend_follows_mujoco_gl_display_and_platform(
    monkeypatch, platform, display, mujoco_gl, mujoco_choice, expected
):
    monkeypatch.setattr(sys, "platform", platform)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    for name, value in (("DISPLAY", display), ("MUJOCO_GL", mujoco_gl)):
        if value:
            monkeypatch.setenv(name, value)
        else:
            monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(headless, "gl_backend", lambda: mujoco_choice)
    assert headless.offscreen_backend() == expected


def test_offscreen_renderer_refuses_glfw_without_display(monkeypatch):
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setenv("MUJOCO_GL", "glfw")
    monkeypatch.setattr(headless, "gl_backend", lambda: "glfw")
    model = mujoco.MjModel.from_xml_string(SPHERE)
    with pytest.raises(RenderError) as info:
        headless.offscreen_renderer(model, 32, 24)
    assert str(info.value) == (
        "cannot create an offscreen OpenGL context: MUJOCO_GL selects MuJoCo's GLFW backend and there is no "
        "display (DISPLAY, WAYLAND_DISPLAY); unset MUJOCO_GL, or set it to egl or osmesa"
    )


def test_renders_headless_after_mujoco_was_imported_first():
    """MuJoCo imported before handsim keeps GLFW; handsim's renderer still renders (EGL), for itself only."""
    done = _fresh_python(
        """
        import sys
        import mujoco
        from mujoco.rendering.classic import gl_context
        from handsim.viz.headless import gl_backend, offscreen_renderer
        from handsim.errors import RenderError
        model = mujoco.MjModel.from_xml_string(sys.argv[1])
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        try:
            renderer = offscreen_renderer(model, 32, 24)
        except RenderError as err:
            if "with the egl backend" not in str(err):  # only a missing EGL skips the test
                raise
            print("NO-GL", err)
            raise SystemExit(0)
        renderer.update_scene(data)
        image = renderer.render()
        renderer.close()
        print(gl_backend(), gl_context.GLContext.__module__, image.shape, image[12, 16].tolist())
        """,
        SPHERE,
    )
    assert done.returncode == 0, done.stderr
    if done.stdout.startswith("NO-GL"):
        pytest.skip(f"no EGL here: {done.stdout.strip()}")
    backend, context_module, rest = done.stdout.strip().split(" ", 2)
    assert (backend, context_module) == ("glfw", "mujoco.glfw")  # MuJoCo's own choice is left as it was
    assert rest.startswith("(24, 32, 3) [")
    red, green, blue = (int(v) for v in rest.split(" [", 1)[1].rstrip("]").split(", "))
    assert red > 200 and green < 100 and blue < 100  # the red sphere fills the image centre


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the headless default is Linux's")
def test_the_ray_workers_gl_setting_leaves_this_process_environment_alone(monkeypatch):
    from handsim.runner.ray_backend import _gl_env

    for name in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    assert _gl_env() == {"MUJOCO_GL": "egl"}
    assert "MUJOCO_GL" not in os.environ
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    assert _gl_env() == {"MUJOCO_GL": "osmesa"}
    monkeypatch.delenv("MUJOCO_GL")
    monkeypatch.setenv("DISPLAY", ":0")
    assert _gl_env() == {}


def test_a_ray_task_sets_the_drivers_choices_in_its_worker_before_the_trial(monkeypatch):
    from handsim.runner.ray_backend import _ray_trial

    for name in ("MUJOCO_GL", "OMP_NUM_THREADS", "HANDSIM_THREADS"):  # unset now, and after the test
        monkeypatch.setenv(name, "")  # recorded, so that what the task sets is undone (delenv of an unset
        monkeypatch.delenv(name)  # name records nothing: MUJOCO_GL=osmesa would outlive this test)
    monkeypatch.setattr("signal.signal", lambda *args: None)  # the worker's Ctrl-C setting: not in a test

    def run(entry, config, frames):
        return (
            entry,
            config,
            frames,
            {k: os.environ.get(k) for k in ("MUJOCO_GL", "OMP_NUM_THREADS", "HANDSIM_THREADS")},
        )

    env = {"OMP_NUM_THREADS": "1", "MUJOCO_GL": "osmesa"}
    assert _ray_trial(run, "entry", "config", 4, env) == (
        "entry",
        "config",
        4,
        {"MUJOCO_GL": "osmesa", "OMP_NUM_THREADS": "1", "HANDSIM_THREADS": "1"},
    )
