"""A synthetic CARMEN log whose truth is known by hand: laps of a square, a scan per true dstate.

The robot drives counter-clockwise round a ``side`` metre square, starting half-way along its south
side, turns +90 degrees on the spot at each corner and ends where it started. Odometry is exact. Each
scan is a pattern of the nearest corner and the heading's sector alone, so the true dstates are 4
corners x 2 (the headings before and after the turn), each seen once per lap, and any two visits to one
true dstate read the same scan.
"""

from pathlib import Path

import numpy as np

BEAMS = 180


def pattern(corner: int, sector: int) -> np.ndarray:
    """The scan seen near ``corner`` (0..3) facing ``sector`` (0..3): a distinct profile for each pair."""
    beams = np.arange(BEAMS)
    return 2.0 + 0.7 * corner + 0.4 * sector + np.sin(beams * (1 + corner + 4 * sector) / 40.0)


def square_poses(laps: int = 2, side: float = 10.0, step: float = 0.25, turn_scans: int = 6) -> list[tuple]:
    """The true (= odometry) poses of ``laps`` laps of the square."""
    corners = np.array([(side, 0.0), (side, side), (0.0, side), (0.0, 0.0)])
    here, heading, poses = np.array([side / 2, 0.0]), 0.0, []
    for leg in range(4 * laps + 1):
        target = corners[leg % 4] if leg < 4 * laps else np.array([side / 2, 0.0])
        n = int(round(np.hypot(*(target - here)) / step))
        for k in range(n):
            poses.append((*(here + (target - here) * k / n), heading))
        here = target
        if leg < 4 * laps:
            for k in range(turn_scans + 1):
                poses.append((*here, heading + np.pi / 2 * k / turn_scans))
            heading += np.pi / 2
    poses.append((*here, heading))
    return [(float(x), float(y), float(np.arctan2(np.sin(h), np.cos(h)))) for x, y, h in poses]


def write_square_log(path: Path, laps: int = 2, side: float = 10.0) -> Path:
    """Write the log as CARMEN lines (TRUEPOS, ODOM, RAWLASER1) and return its path."""
    corners = np.array([(side, 0.0), (side, side), (0.0, side), (0.0, 0.0)])
    lines = ["# synthetic: laps of a square, written by tests/ingest/synthetic.py"]
    for i, (x, y, h) in enumerate(square_poses(laps, side)):
        corner = int(np.argmin(np.hypot(*(corners - (x, y)).T)))
        sector = int(np.rint(h / (np.pi / 2))) % 4
        ranges = " ".join(f"{r:.3f}" for r in pattern(corner, sector))
        t = 0.1 * i
        lines += [f"TRUEPOS {x!r} {y!r} {h!r} {x!r} {y!r} {h!r} {t:.2f} h {t:.2f}",
                  f"ODOM {x!r} {y!r} {h!r} 0 0 0 {t:.2f} h {t:.2f}",
                  f"RAWLASER1 0 -1.5708 3.1416 0.017453 50 0.01 0 {BEAMS} {ranges} 0 {t:.2f} h {t:.2f}"]
    path.write_text("\n".join(lines) + "\n")
    return path
