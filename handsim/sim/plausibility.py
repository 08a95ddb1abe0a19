"""Plausibility gates: inputs that cannot give a meaningful physical answer are refused or flagged.

A replay always returns its numbers; these gates say when the numbers mean nothing, so that a user never
reads "held" or "warnings none" off a trial that could not have been judged.

* :func:`check_control_rate` refuses a control rate too low for the metrics: a control frame must be at
  most half the shortest time the metrics judge (:func:`min_control_rate`).
"""

from __future__ import annotations

import math
import numbers

from handsim.sim.metrics import MetricSpec


def shortest_judged_time(spec: MetricSpec) -> float:
    """The shortest time the metrics judge, s: the contact gap, or the release delay when shorter (and > 0).

    The glove scenario's contact gap (``spec.contact_gap``: an object untouched this long is lost) and
    release delay (``spec.release_delay``: the grip acts this long before the support goes off; 0 = at
    once, which times nothing).
    """
    times = [spec.contact_gap] + ([spec.release_delay] if spec.release_delay > 0 else [])
    return min(times)


def min_control_rate(spec: MetricSpec) -> float:
    """The lowest control rate the metrics can be judged at, Hz.

    Two control frames within :func:`shortest_judged_time`. At the defaults (0.1 s contact gap and release
    delay) that is 20 Hz; the recordings handsim reads are sampled at 30 Hz (Tzionas, ARCTIC) to 60 Hz
    (GraspDB14), and the default control rate is 100 Hz.

    Args:
        spec: The metric parameters.

    Returns:
        The minimum control rate, Hz.
    """
    return 2.0 / shortest_judged_time(spec)


def check_control_rate(rate_hz: float, spec: MetricSpec) -> float:
    """A control rate as a float, refused when it is not a number or below :func:`min_control_rate`.

    Args:
        rate_hz: The requested control rate, Hz.
        spec: The metric parameters it must resolve.

    Returns:
        The rate, Hz.

    Raises:
        ValueError: The rate is not a finite number, or is below the minimum; the message says why.
    """
    minimum = min_control_rate(spec)
    shortest = shortest_judged_time(spec)
    number = isinstance(rate_hz, numbers.Real) and not isinstance(rate_hz, bool)
    rate = float(rate_hz) if number else math.nan
    if not (math.isfinite(rate) and rate >= minimum):
        got = f"{rate:g}" if number else repr(rate_hz)
        raise ValueError(
            f"expected a control rate of at least {minimum:g} Hz (two control frames within the "
            f"{shortest:g} s contact gap and release delay the metrics judge), got {got}"
        )
    return rate
