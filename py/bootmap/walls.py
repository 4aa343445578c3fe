"""Wall directions in a laser scan, and the rotations between two scans they allow.

Walls are straight, and the directions the walls run in, as a robot sees them, turn with the robot: a turn
of 90 degrees shifts every wall's direction in the scan by -90. So the rotation between two scans is where
their histograms of wall directions agree (the angle histograms of Weiss, Wetzler and von Puttkamer, IROS
1994); the scans need not overlap. A wall has no sense and a building's walls repeat their directions (a
rectangular building's every 90 degrees), so the histograms say the rotation only up to those repeats:
:func:`rotation_candidates` gives each rotation they allow, with its strength.

Pure functions of a scan and the laser's geometry, shared by the simulator's turn law (which follows a
turn from one scan to the next) and the map's compass (which reads each action's angle from the images at
its ends, :mod:`bootmap.mapping.compass`).
"""

from __future__ import annotations

import numpy as np

#: Each beam's point is fitted with its neighbours within this many metres either side along the wall,
#: and at least and at most so many neighbours either side.
HALF_LENGTH_M, HALF_WINDOW, MAX_HALF_WINDOW = 0.5, 4, 30
#: A fit is a wall where the points' spread across the line is at most this share of their spread along it.
FLATNESS = 0.05
#: Points more than this far apart (plus this share of their range) are not on one wall.
GAP_M, GAP_SHARE = 0.3, 0.05
#: Ranges at or beyond this share of the laser's maximum are "nothing seen", not a wall.
MAX_RANGE_SHARE = 0.98
#: Histogram bins per degree of wall direction, and the smoothing (degrees, s.d.) of one vote.
BINS, SMOOTH_DEG = 180, 2.0
#: A correlation peak is a candidate where it reaches this share of the highest.
PEAK_SHARE = 0.25


def wrap_deg(a: float) -> float:
    """An angle into [-180, 180)."""
    return (a + 180.0) % 360.0 - 180.0


def wall_directions(image, beam_angles: np.ndarray, range_max: float) -> np.ndarray:
    """The histogram of wall directions in one laser image: per degree of direction (0-179, a wall has no
    sense), the metres of wall seen running that way, smoothed. Each beam's point is fitted with
    :data:`HALF_WINDOW` neighbours either side; where those are too few to see a wall through the range
    noise (near the robot, where points crowd), with the neighbours within :data:`HALF_LENGTH_M` either
    side along the wall."""
    r = np.asarray(image, dtype=float)
    n = len(r)
    seen = np.isfinite(r) & (r > 0.05) & (r < MAX_RANGE_SHARE * range_max)
    r0 = np.where(seen, r, 0.0)
    x, y = r0 * np.cos(beam_angles), r0 * np.sin(beam_angles)
    # a step from one point to the next that leaves the wall (or a beam that saw nothing)
    hop = np.hypot(np.diff(x), np.diff(y))
    broken = (~(seen[:-1] & seen[1:]) | (hop > GAP_M + GAP_SHARE * np.minimum(r0[:-1], r0[1:]))).astype(float)
    spacing = max(float(np.median(np.abs(np.diff(beam_angles)))), 1e-6)
    by_length = np.ceil(HALF_LENGTH_M / np.maximum(r0, 1e-3) / spacing)
    votes = np.full(n, np.nan)
    for half in (np.full(n, HALF_WINDOW), np.clip(by_length, HALF_WINDOW, MAX_HALF_WINDOW).astype(int)):
        flat, direction = _line_fits(x, y, seen, broken, half)
        votes = np.where(np.isnan(votes) & flat, direction, votes)
    # Each point votes with the length of wall it stands for: the distance between its neighbours, halved.
    length = np.zeros(n)
    length[1:-1] = np.hypot(x[2:] - x[:-2], y[2:] - y[:-2]) / 2
    voting = ~np.isnan(votes)
    hist = np.bincount((votes[voting] * BINS / 180.0).astype(int) % BINS, weights=length[voting], minlength=BINS)
    return _smooth(hist)


def _line_fits(x: np.ndarray, y: np.ndarray, seen: np.ndarray, broken: np.ndarray, half: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Per point, whether it and its ``half`` neighbours either side lie on one straight wall (all seen,
    no step off the wall, flat: :data:`FLATNESS`), and the wall's direction (degrees, 0-180)."""
    n = len(x)
    i = np.arange(n)
    lo, hi = i - half, i + half  # inclusive
    inside = seen & (lo >= 0) & (hi < n)
    lo, hi = np.clip(lo, 0, n - 1), np.clip(hi, 0, n - 1)

    def window_sum(v: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        c = np.concatenate([[0.0], np.cumsum(v)])
        return c[b + 1] - c[a]

    whole = inside & (window_sum(broken, lo, np.maximum(hi - 1, lo)) == 0)
    m = (hi - lo + 1).astype(float)
    sx, sy = window_sum(x, lo, hi), window_sum(y, lo, hi)
    sxx = window_sum(x * x, lo, hi) - sx * sx / m
    syy = window_sum(y * y, lo, hi) - sy * sy / m
    sxy = window_sum(x * y, lo, hi) - sx * sy / m
    half_tr, root = (sxx + syy) / 2, np.sqrt(((sxx - syy) / 2) ** 2 + sxy ** 2)
    lam_max, lam_min = half_tr + root, half_tr - root
    flat = whole & (lam_max > 0) & (lam_min <= FLATNESS * np.maximum(lam_max, 1e-12))
    return flat, np.degrees(0.5 * np.arctan2(2 * sxy, sxx - syy)) % 180.0


def _kernel_spectrum() -> np.ndarray:
    """The spectrum of one vote's smoothing (a Gaussian of :data:`SMOOTH_DEG` on the circle of directions)."""
    k = np.arange(BINS)
    d = np.minimum(k, BINS - k) * (180.0 / BINS)
    return np.fft.fft(np.exp(-0.5 * (d / SMOOTH_DEG) ** 2))


#: Computed once: every histogram is smoothed by the same kernel.
_KERNEL_SPECTRUM = _kernel_spectrum()


def _smooth(hist: np.ndarray) -> np.ndarray:
    """The histogram smoothed on the circle (a Gaussian of :data:`SMOOTH_DEG`)."""
    return np.real(np.fft.ifft(np.fft.fft(hist) * _KERNEL_SPECTRUM))


def rotation_candidates(before: np.ndarray, after: np.ndarray) -> list[tuple[float, float]]:
    """The rotations (degrees, in [-180, 180)) that bring the walls seen ``before`` onto those seen
    ``after``: each peak of the histograms' circular correlation of at least :data:`PEAK_SHARE` of the
    highest, a direction modulo 180 degrees, so two candidates per peak, each with its strength (its
    peak's share of the highest). Empty where either image shows no wall."""
    if before.max(initial=0.0) <= 0 or after.max(initial=0.0) <= 0:
        return []
    # c[d] = sum over phi of before[phi] * after[phi - d]: a wall at phi before the turn is at phi - d after.
    c = np.real(np.fft.ifft(np.fft.fft(before) * np.conj(np.fft.fft(after))))
    top = c.max()
    if top <= 0:
        return []
    # the peaks, each refined by the parabola through it and its neighbours
    y0, y2 = np.roll(c, 1), np.roll(c, -1)
    out = []
    for d in np.flatnonzero((c >= y0) & (c > y2) & (c >= PEAK_SHARE * top)).tolist():
        a, b, e = float(y0[d]), float(c[d]), float(y2[d])
        den = a - 2 * b + e
        peak = (d + (0.5 * (a - e) / den if den < 0 else 0.0)) * (180.0 / BINS)
        out += [(wrap_deg(peak), b / top), (wrap_deg(peak + 180.0), b / top)]
    return out
