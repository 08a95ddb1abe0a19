"""Presentation: plots, trajectory reports, rendered frames and videos, and the headless OpenGL choice.

Nothing below this package (data types, readers, builders, simulation, trials) imports it; the
environments' ``render()``, the dataset runner's renders, the report and the CLI do.
"""
