"""Data bundled with handsim: only files the package may redistribute (with their notices)."""

from pathlib import Path

ASSETS_DIR = Path(__file__).resolve().parent
