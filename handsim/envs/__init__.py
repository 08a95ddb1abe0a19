"""Gymnasium environments of handsim (none are registered yet)."""
