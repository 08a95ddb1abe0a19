"""Dimensions shared by the GraspDB14 objects' table and their meshes: no mesh library needed.

The bottle crate is a set of boxes (its exact collision shape); :func:`crate_boxes` gives their corners,
from which both its primitives (:mod:`handsim.builders.graspdb_objects`) and its mesh
(:mod:`handsim.builders.graspdb_meshes`) are made. All lengths in mm unless named otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from handsim.datatypes.object_model import Primitive

MM = 1e-3  # metres per millimetre: all geometry is written in mm
Q_Z_TO_X = (math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0)  # 90° about y: a cylinder's local z along object x

# Bottle crate: an empty 20 × 0.5 l beer crate (4 × 5 cells) with a central handle, outer 400 × 300 × 290 mm.
CRATE_L, CRATE_W, CRATE_H = 400.0, 300.0, 290.0
CRATE_WALL, CRATE_FLOOR, CRATE_DIVIDER, CRATE_DIVIDER_H = 4.0, 4.0, 3.0, 150.0
CRATE_BAR = ((-80.0, -12.5, 120.0), (80.0, 12.5, 145.0))  # handle bar corners (centred frame)
CRATE_POST_X, CRATE_POST_HW = (60.0, 80.0), 6.0  # handle posts: |x| range and half-width in y


def box_primitive(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Primitive:
    """A box primitive (metres) spanning the corners ``lo``..``hi`` given in mm."""
    half = (np.asarray(hi, float) - np.asarray(lo, float)) / 2 * MM
    pos = (np.asarray(hi, float) + np.asarray(lo, float)) / 2 * MM
    return Primitive("box", tuple(map(float, half)), (float(pos[0]), float(pos[1]), float(pos[2])))


def crate_boxes() -> tuple[tuple[tuple[float, float, float], tuple[float, float, float]], ...]:
    """Corners (mm, centred frame) of every box of the crate: floor, 4 walls, dividers, handle."""
    lx, wy, hz = CRATE_L / 2, CRATE_W / 2, CRATE_H / 2
    t, f, d = CRATE_WALL, CRATE_FLOOR, CRATE_DIVIDER / 2
    z0, z1, zd = -hz, -hz + f, -hz + f + CRATE_DIVIDER_H
    ix, iy = lx - t, wy - t  # inner half-sizes
    boxes = [
        ((-lx, -wy, z0), (lx, wy, z1)),  # floor
        ((-lx, -wy, z1), (lx, -iy, hz)),  # long walls
        ((-lx, iy, z1), (lx, wy, hz)),
        ((-lx, -iy, z1), (-ix, iy, hz)),  # short walls
        ((ix, -iy, z1), (lx, iy, hz)),
    ]
    ys = [-iy + k * (2 * iy) / 4 for k in range(1, 4)]  # longitudinal dividers (run along x)
    xs = [-ix + k * (2 * ix) / 5 for k in range(1, 5)]  # transverse dividers, cut by the longitudinal ones
    boxes += [((-ix, y - d, z1), (ix, y + d, zd)) for y in ys]
    y_edges = [-iy, *(e for y in ys for e in (y - d, y + d)), iy]
    for x in xs:
        boxes += [((x - d, y_edges[i], z1), (x + d, y_edges[i + 1], zd)) for i in range(0, len(y_edges), 2)]
    px0, px1 = CRATE_POST_X
    bar_lo, bar_hi = CRATE_BAR
    for lo_x, hi_x in ((-px1, -px0), (px0, px1)):
        boxes.append(((lo_x, -CRATE_POST_HW, zd), (hi_x, CRATE_POST_HW, bar_lo[2])))
    boxes.append((bar_lo, bar_hi))
    return tuple(boxes)
