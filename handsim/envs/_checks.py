"""Keyword checks the environments share: a number that must be finite and ≥ 0, or finite and > 0."""

from __future__ import annotations

import math


def nonnegative(name: str, value: float) -> float:
    """``value`` as a float when it is finite and ≥ 0.

    Raises:
        ValueError: It is not (the message names the keyword ``name``).
    """
    value = float(value)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be a finite number ≥ 0, got {value}")
    return value


def positive(name: str, value: float) -> float:
    """``value`` as a float when it is finite and > 0.

    Raises:
        ValueError: It is not (the message names the keyword ``name``).
    """
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number > 0, got {value}")
    return value
