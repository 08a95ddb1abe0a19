"""Simulation layer: the only place that compiles specs and steps MuJoCo."""

from handsim.sim.scene.model import ModelSummary, compile_spec, summarize
from handsim.sim.warnings import WARNING_NAMES, raise_on_warnings, warning_counts

__all__ = [
    "WARNING_NAMES",
    "ModelSummary",
    "compile_spec",
    "raise_on_warnings",
    "summarize",
    "warning_counts",
]
