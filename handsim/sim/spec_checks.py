"""Checks every parameter spec of the simulation layer makes on construction (metrics, placement, stability).

A spec is written into each result; one made from a file of another handsim version, or with a threshold
that is not a finite positive number, is refused with the field's name and value.
"""

from __future__ import annotations

import math
from collections.abc import Iterable


def check_version(version: str, known: str, what: str) -> None:
    """Refuse a spec of another version.

    Args:
        version: The spec's ``version`` field.
        known: The version this handsim writes.
        what: The spec's name in the message, e.g. ``"metric"``.

    Raises:
        ValueError: ``version`` is not ``known``.
    """
    if version != known:
        raise ValueError(f"unknown {what} spec version {version!r}; this handsim knows {known!r}")


def check_positive(spec: object, names: Iterable[str], label: str = "") -> None:
    """Refuse a field that is not a positive finite number.

    Args:
        spec: The spec.
        names: The fields that must be positive and finite.
        label: Put before the field's name in the message (``"placement "``).

    Raises:
        ValueError: The first such field that is not, with its value.
    """
    for name in names:
        value = getattr(spec, name)
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{label}{name} must be a positive finite number, got {value}")


def check_nonnegative(spec: object, names: Iterable[str], label: str = "") -> None:
    """Refuse a field that is not a finite number ≥ 0 (arguments as :func:`check_positive`).

    Raises:
        ValueError: The first such field that is not, with its value.
    """
    for name in names:
        value = getattr(spec, name)
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{label}{name} must be a finite number ≥ 0, got {value}")
