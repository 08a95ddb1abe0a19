"""Checks the environments share: keyword numbers (finite and ≥ 0, or > 0) and ``reset`` options."""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from typing import Any


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


def set_checked(instance: object, checks: Mapping[str, Callable[[str, float], float]]) -> None:
    """Replace named numbers of a frozen dataclass by their checked floats (:func:`nonnegative`, …).

    For a ``__post_init__``: the keywords an environment takes are checked where they are grouped.

    Args:
        instance: The dataclass instance.
        checks: Field name → its check, called with the name (for the message) and the value.

    Raises:
        ValueError: A value fails its check (the message names the field).
    """
    for name, check in checks.items():
        object.__setattr__(instance, name, check(name, getattr(instance, name)))


def reset_options(options: object, allowed: Mapping[str, str], owner: str) -> Mapping[str, Any]:
    """The ``options`` of a ``reset`` call, checked: None (no options) or a dict of known keys.

    Args:
        options: What the caller passed.
        allowed: The option names the environment takes → what each is, for the message.
        owner: The environment's class name, for the message.

    Returns:
        The options (an empty dict for None).

    Raises:
        TypeError: ``options`` is neither None nor a dict.
        ValueError: It holds a key the environment does not take (the message lists its options); an
            environment that takes none says so.
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise TypeError(
            f"{owner}.reset: options must be a dict or None, got {type(options).__name__} {options!r}"
        )
    unknown = sorted((repr(k) for k in options if k not in allowed), key=str)
    if not unknown:
        return options
    if not allowed:
        raise ValueError(f"{owner}.reset takes no options, got {', '.join(unknown)}")
    listing = "; ".join(f"{name!r} ({what})" for name, what in allowed.items())
    raise ValueError(f"{owner}.reset: unknown option {', '.join(unknown)}; its options are {listing}")


def whole_option(options: Mapping[str, Any], name: str) -> int:
    """The option ``name`` as an int when it is a whole number (a Python or NumPy integer, not a bool).

    A float such as 2.7 is not rounded into a frame, nor ``True`` read as 1.

    Raises:
        TypeError: The value is not an integer (the message names the option and gives the value).
    """
    value = options[name]
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(
            f"options[{name!r}] must be a whole number (int), got {type(value).__name__} {value!r}"
        )
    return int(value)
