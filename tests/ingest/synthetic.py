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


def corrected_lines(poses: list[tuple], side: float = 10.0) -> list[str]:
    """The square's scans at ``poses`` as a gmapping-corrected CARMEN log: a ``FLASER`` with the
    corrected pose in both pose fields, an ``ODOM`` restarting from it, and an ``ODOM`` at the next
    scan's pose (odometry's exact prediction of it); ``PARAM`` lines first, as in the real logs."""
    corners = np.array([(side, 0.0), (side, side), (0.0, side), (0.0, 0.0)])
    lines = ["PARAM robot_front_laser_max 80.0 nohost 0"]
    for i, (x, y, h) in enumerate(poses):
        corner = int(np.argmin(np.hypot(*(corners - (x, y)).T)))
        sector = int(np.rint(h / (np.pi / 2))) % 4
        ranges = " ".join(f"{r:.3f}" for r in pattern(corner, sector))
        pose, t = f"{x:.6f} {y:.6f} {h:.6f}", 0.1 * i
        if i:
            lines.append(f"ODOM {pose} 0 0 0 {t - 0.01:.2f} h {t - 0.01:.2f}")
        lines += [f"FLASER {BEAMS} {ranges} {pose} {pose} {t:.2f} h {t:.2f}",
                  f"ODOM {pose} 0 0 0 {t:.2f} h {t:.2f}"]
    return lines


def write_corrected_log(path: Path, scans: int, start: int = 16, side: float = 10.0) -> Path:
    """``scans`` scans of laps of the square, from scan ``start`` of :func:`square_poses` on, as a
    corrected CARMEN log, gzip compressed when ``path`` ends in ``.gz``; returns ``path``. From the
    default start, the first corner's turn runs from the 5th scan to the 11th, 15 degrees a scan."""
    import gzip

    poses = square_poses(laps=2, side=side)[start:start + scans]
    text = "\n".join(corrected_lines(poses, side)) + "\n"
    if path.suffix == ".gz":
        with gzip.open(path, "wt") as f:
            f.write(text)
    else:
        path.write_text(text)
    return path


#: A ring corridor round a block: the outer walls (x, y from 0 to these) and the corridor's width along
#: its south, east, north and west sides, all different, so that no two corners look alike.
RING_SIZE, RING_WIDTHS = (24.0, 16.0), (1.6, 3.0, 2.6, 2.4)


def ring_walls(size=RING_SIZE, widths=RING_WIDTHS) -> np.ndarray:
    """The ring corridor's walls: the outer rectangle and the block inside it."""
    from support.raycast import polygon_walls

    (w, h), (south, east, north, west) = size, widths
    outer = polygon_walls([(0, 0), (w, 0), (w, h), (0, h)])
    inner = polygon_walls([(west, south), (w - east, south), (w - east, h - north), (west, h - north)])
    return np.vstack([outer, inner])


def ring_poses(laps: int = 2, size=RING_SIZE, widths=RING_WIDTHS, step: float = 0.5) -> list[tuple]:
    """Laps of the ring corridor along its centre lines, counter-clockwise, turning on the spot at the
    corners."""
    (w, h), (south, east, north, west) = size, widths
    corners = [(w - east / 2, south / 2), (w - east / 2, h - north / 2), (west / 2, h - north / 2),
               (west / 2, south / 2)]
    start = (w / 2, south / 2)
    points = [start] + corners * laps + [start]
    poses = []
    for a, b in zip(points, points[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        heading = float(np.arctan2(*(b - a)[::-1]))
        n = max(int(round(np.hypot(*(b - a)) / step)), 1)
        poses += [(*(a + (b - a) * k / n), heading) for k in range(n)]
    return [(float(x), float(y), float(t)) for x, y, t in poses] + [(*map(float, points[-1]), poses[-1][2])]


def write_drive_log(path: Path, walls: np.ndarray, poses: list[tuple], gaps=()) -> Path:
    """A drive through a building drawn as walls, as a gmapping-corrected CARMEN log: per pose a ``FLASER``
    of 180 beams ray-cast from it (the pose in both pose fields), an ``ODOM`` restarting from it and one at
    the next pose (exact odometry), except before the scans in ``gaps`` (the wheels recorded nothing)."""
    from support.raycast import cast

    lines = []
    for i, pose in enumerate(poses):
        ranges = " ".join(f"{r:.3f}" for r in cast(walls, pose, beams=180, max_range=81.9))
        p = " ".join(repr(v) for v in pose)
        t = float(i)
        lines += [f"FLASER 180 {ranges} {p} {p} {t} h {t}", f"ODOM {p} 0 0 0 0 h 0"]
        if i + 1 < len(poses) and i + 1 not in gaps:
            n = " ".join(repr(v) for v in poses[i + 1])
            lines.append(f"ODOM {n} 0 0 0 {t + 1} h {t + 1}")
    path.write_text("\n".join(lines) + "\n")
    return path
