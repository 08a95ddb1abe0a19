"""The package version, in one place: ``pyproject.toml`` reads it, records and ``--version`` print it.

A module of its own (not ``handsim/__init__.py``) so that any layer can name the version without importing
the package's ``__init__`` — which registers the gymnasium environments, the top layer.
"""

__version__ = "0.1.0"
