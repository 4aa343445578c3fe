"""A 2-D laser ray-cast by hand: synthetic laser images of rooms drawn as wall segments."""

from __future__ import annotations

import math

import numpy as np


def polygon_walls(corners) -> np.ndarray:
    """The walls of a closed polygon: (n, 4) segments x0, y0, x1, y1."""
    c = np.asarray(corners, dtype=float)
    return np.column_stack([c, np.roll(c, -1, axis=0)])


#: An 8 m x 5 m room with a 1 m pillar, and an L-shaped corridor 2 m wide, 12 m x 10 m.
ROOM = np.vstack([polygon_walls([(0, 0), (8, 0), (8, 5), (0, 5)]),
                  polygon_walls([(5, 1), (6, 1), (6, 2), (5, 2)])])
CORRIDOR = polygon_walls([(0, 0), (12, 0), (12, 10), (10, 10), (10, 2), (0, 2)])


def cast(walls: np.ndarray, pose, beams: int = 180, max_range: float = 20.0, noise_m: float = 0.0,
         rng=None, fov_deg: float = 180.0) -> np.ndarray:
    """The laser image seen from ``pose`` (x, y, theta): ``beams`` ranges from -90 to +90 degrees (all
    round from -180 with ``fov_deg=360``, bootmap.surfaces.beam_angles), the nearest wall along each beam,
    ``max_range`` where none is closer; Gaussian range noise ``noise_m``."""
    from bootmap.surfaces import beam_angles

    x, y, theta = pose
    angles = theta + beam_angles(beams, fov_deg)
    d = np.column_stack([np.cos(angles), np.sin(angles)])  # (beams, 2)
    p, q = walls[:, :2], walls[:, 2:] - walls[:, :2]  # wall start, direction (walls, 2)
    w = p - np.array([x, y])
    denom = d[:, None, 0] * q[None, :, 1] - d[:, None, 1] * q[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[None, :, 0] * q[None, :, 1] - w[None, :, 1] * q[None, :, 0]) / denom  # along the beam
        u = (w[None, :, 0] * d[:, None, 1] - w[None, :, 1] * d[:, None, 0]) / denom  # along the wall
    hit = (np.abs(denom) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
    r = np.where(hit, t, np.inf).min(axis=1)
    if noise_m:
        r = r + (rng or np.random.default_rng(0)).normal(0.0, noise_m, beams)
    return np.minimum(r, max_range)
