"""Scan matching: how alike two laser images are once the second is moved onto the first.

Two visits to one place rarely stand on the same spot facing the same way, so their raw range vectors
differ although they saw the same walls. This module aligns the two scans as point sets (a rigid motion of
the plane: a shift and a turn) and scores how much of each scan the other explains once aligned. It reads
images only (the tableau's 180 ranges from -90 to +90 degrees in the robot's frame), never poses.

Method
------
1. **Points.** Every beam that saw something (range below ``max_range``) gives a return, a 2-D point in the
   robot's frame.
2. **Surfaces.** Consecutive returns are joined into one surface when they are no farther apart than a
   wall seen at ``max_incidence_deg`` from its normal would space them (``r * beam step / cos(incidence)``,
   plus the inlier distance for range noise); each joined piece is sampled every ``resolution_m`` (a map
   cell). A scan's surface is its returns as an occupancy map would draw them, so a return of the other
   scan that falls on the wall between two beams counts as explained, at any range.
3. **Alignment.** Two visits may face any way and stand up to a place's radius apart, beyond what ICP
   pulls in, so a global search comes first: a correlative search (as in Olson's and Cartographer's
   scan matchers) scores every heading ``search_step_deg`` apart and every shift ``search_step_m`` apart
   within ``place_radius_m``, by summing over ``b``'s returns (every ``search_stride``-th) a likelihood
   field of ``a``'s surface (a Gaussian of the distance to it, as wide as the shift step). The ``refine``
   best candidates are refined by point-to-point ICP (``small_gicp``, Koide's library; the 2-D points lie
   at z = 0) of ``b``'s returns onto ``a``'s surface, with correspondences reaching ``coarse_m``, then
   ``fine_m``, then ``inlier_m`` (which drops returns the other scan never saw). The candidate of highest
   score wins, among those ICP leaves within ``place_radius_m``: a match says the two visits are one place,
   so an alignment that only fits with them farther apart (ICP slid along a corridor, or onto a room
   beside) is no match of it. No candidate left: the score is 0.
4. **Score.** Once aligned, a return *is explained* when it lies within ``inlier_m`` of the other scan's
   surface, and *refuted* when it is not explained but lies nearer than what the other scan's beam towards
   it (and both neighbouring beams) saw: the other visit's laser passed through that spot, so no wall can
   be there. A beam that saw nothing refutes nothing (a drop-out reads the same as open space). The score
   is the net share of the returns of both scans that the other visit confirms::

       score = max(0, explained - refuted) / (returns of a + returns of b)

   Its meaning in the domain: the part of what the robot saw on the two visits that can be one and the
   same set of walls seen from two poses, less what one visit shows to be open space. It lies in [0, 1],
   1 when every return of each scan lies on a surface the other saw; it is comparable across pairs because
   it is a share, not a sum of squared residuals (which would favour scans with few returns). Refutations
   matter in buildings: walls at right angles line up in many wrong ways, but a wrong alignment puts walls
   where the other visit saw through. Parts a scan could not see (behind the robot:
   the laser covers 180 degrees; occluded; beyond ``max_range``) lower it, so two visits of one place
   facing opposite ways can score low: the laser did not see the same walls. An image with no return
   scores 0 with anything.

Parameters come from the sensor and the domain, not from fitting any log: a SICK-class laser's range noise
is 1-3 cm; a map cell is 5 cm; a return is explained within 10 cm (two cells, about three standard
deviations of the noise plus what is left of the alignment error); a place has a radius of about 3 m, which
bounds the search's shifts; the search's steps (0.5 m, 10 degrees: 0.35 m at 4 m) leave the truth within
ICP's 1 m first reach, then 30 cm.

Many images: :meth:`ScanMatcher.scores` scores every pair, or, with ``shortlist=k``, only each image's k
likeliest partners by the correlative search's best fit (step 3 alone, a tenth of a match's cost), as place
recognition retrieves candidates cheaply and verifies them geometrically; the rest score 0.

Matching is symmetric: :meth:`ScanMatcher.match` aligns the pair in one canonical order and inverts the
motion when asked the other way round, so ``match(a, b)`` and ``match(b, a)`` have the same score and
inverse transforms.

Examples
--------
>>> import numpy as np
>>> room = np.full(180, 20.0); room[40:140] = 4.0
>>> m = ScanMatcher().match(room, room)
>>> round(m.score, 2), [round(v, 3) + 0.0 for v in m.transform]
(1.0, [0.0, 0.0, 0.0])
>>> ScanMatcher().match(room, np.full(180, 20.0)).score
0.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .proc import in_processes
from .surfaces import beam_step, image_points, in_3d, planar, se2, surface_points

__all__ = ["Match", "ScanMatcher", "image_points", "surface_points"]


@dataclass(frozen=True)
class Match:
    """The best alignment of image ``b`` onto image ``a``.

    Attributes
    ----------
    score : float
        Share of the returns of both images explained by the other once aligned, in [0, 1].
    transform : tuple of float
        ``(dx, dy, dtheta)``: the pose of ``b``'s robot frame in ``a``'s (metres, metres, radians in
        [-pi, pi)); a point ``p`` seen by ``b`` is at ``R(dtheta) p + (dx, dy)`` in ``a``'s frame. For two
        visits with poses ``pa`` and ``pb`` this estimates ``pa^-1 (+) pb``.
    inliers : tuple of int
        Returns of ``a`` explained by ``b``, returns of ``b`` explained by ``a``.
    points : tuple of int
        Returns of ``a`` and of ``b`` (beams that saw something).
    """

    score: float
    transform: tuple[float, float, float]
    inliers: tuple[int, int]
    points: tuple[int, int]
    refuted: tuple[int, int] = (0, 0)


class _Scan:
    """One image made ready for matching: its returns, its surface and the surface's k-d tree."""

    __slots__ = ("ranges", "step", "all_round", "points", "points3", "sparse", "surface_tree", "surface_cloud", "field",
                 "origin")

    def __init__(self, image, matcher: "ScanMatcher"):
        import small_gicp

        r = np.asarray(image, dtype=float).ravel()
        # A beam that saw nothing is no evidence of free space (a drop-out reads the same): never refutes.
        self.ranges = np.where(np.isfinite(r) & (r > 0.0) & (r < matcher.max_range), r, -np.inf)
        self.step = beam_step(len(r), matcher.fov_deg)
        self.all_round = matcher.fov_deg >= 360.0
        self.points = image_points(image, matcher.max_range, matcher.fov_deg)
        self.points3 = in_3d(self.points)
        self.sparse = self.points[::matcher.search_stride]
        surface = surface_points(image, matcher.max_range, matcher.resolution_m, matcher.max_incidence_deg,
                                 matcher.inlier_m, matcher.fov_deg)
        if len(surface):
            surface3 = in_3d(surface)
            self.surface_cloud = small_gicp.PointCloud(surface3)
            self.surface_tree = small_gicp.KdTree(self.surface_cloud)
            self.field, self.origin = _likelihood_field(surface, matcher.search_step_m, matcher.place_radius_m)
        else:
            self.surface_cloud = self.surface_tree = self.field = self.origin = None

    def correlate(self, turned: np.ndarray, shifts: np.ndarray) -> np.ndarray:
        """The summed likelihood field at points ``turned`` (R, P, 2), each set moved by every shift of
        ``shifts`` (S, 2, whole cells away from the field's padding): an (R, S) array."""
        h, w = self.field.shape
        pad = int(np.abs(shifts).max() / _FIELD_CELL_M + 0.5) + 1
        ij = np.rint((turned - self.origin) / _FIELD_CELL_M).astype(np.intp)
        core = (ij[..., 0] >= pad) & (ij[..., 0] < h - pad) & (ij[..., 1] >= pad) & (ij[..., 1] < w - pad)
        flat = np.where(core, ij[..., 0] * w + ij[..., 1], pad * w + pad)
        step = np.rint(shifts / _FIELD_CELL_M).astype(np.intp)
        values = self.field.ravel()[flat[:, None, :] + (step[:, 0] * w + step[:, 1])[None, :, None]]
        return (values * core[:, None, :]).sum(axis=-1)

    def judge(self, points3: np.ndarray, inlier_m: float) -> tuple[int, int]:
        """Of ``points3`` (n x 3, in this scan's frame): how many this scan explains (within ``inlier_m`` of
        its surface) and how many it refutes (not explained, and closer than what this scan's beams
        towards them, and their neighbours', saw: the laser saw through them)."""
        if self.surface_tree is None or len(points3) == 0:
            return 0, 0
        _, sq = self.surface_tree.batch_nearest_neighbor_search(points3)
        explained = np.asarray(sq) <= inlier_m * inlier_m
        rho = np.hypot(points3[:, 0], points3[:, 1])
        n = len(self.ranges)
        bearing = np.arctan2(points3[:, 1], points3[:, 0])
        if self.all_round:
            b = np.rint((bearing + math.pi) / self.step).astype(int) % n
            inside = np.ones(len(b), dtype=bool)
            before, after = (b - 1) % n, (b + 1) % n
        else:
            beam = np.rint((bearing + math.pi / 2) / self.step).astype(int)
            inside = (beam >= 0) & (beam < n)
            b = np.clip(beam, 0, n - 1)
            before, after = np.maximum(b - 1, 0), np.minimum(b + 1, n - 1)
        seen = np.minimum(np.minimum(self.ranges[b], self.ranges[before]), self.ranges[after])
        refuted = inside & ~explained & (rho < seen - inlier_m)
        return int(np.count_nonzero(explained)), int(np.count_nonzero(refuted))


#: Cell of the likelihood field of the correlative search (m): a fifth of its 0.5 m translation step.
_FIELD_CELL_M = 0.1


def _likelihood_field(surface: np.ndarray, sigma_m: float, pad_m: float) -> tuple[np.ndarray, np.ndarray]:
    """A grid around ``surface`` holding ``exp(-d^2 / (2 sigma^2))`` of the distance ``d`` to it, padded by
    ``pad_m`` more (the search's reach), and the grid's corner."""
    from scipy.ndimage import distance_transform_edt

    margin = 3 * sigma_m + pad_m + 2 * _FIELD_CELL_M
    origin = surface.min(axis=0) - margin
    shape = np.ceil((surface.max(axis=0) + margin - origin) / _FIELD_CELL_M).astype(int) + 1
    occupied = np.ones(shape, dtype=bool)
    ij = np.floor((surface - origin) / _FIELD_CELL_M).astype(int)
    occupied[ij[:, 0], ij[:, 1]] = False
    d = distance_transform_edt(occupied) * _FIELD_CELL_M
    return np.exp(-0.5 * (d / sigma_m) ** 2).astype(np.float32), origin


def _inverse(t: tuple[float, float, float]) -> tuple[float, float, float]:
    x, y, theta = t
    c, s = math.cos(theta), math.sin(theta)
    return -c * x - s * y, s * x - c * y, (-theta + math.pi) % (2 * math.pi) - math.pi


class ScanMatcher:
    """Scan matching of laser images by multi-start ICP; see the module docstring for the method.

    Parameters
    ----------
    max_range : float
        The laser reading that means nothing was seen (m): the images' clip range.
    inlier_m : float
        A return is explained by the other scan when it lies within this distance of that scan's surface
        (m): two 5 cm map cells, about three standard deviations of a laser's 1-3 cm range noise plus the
        alignment's residual error.
    resolution_m : float
        Spacing of the samples along a surface (m): the resolution of an occupancy map.
    max_incidence_deg : float
        Steepest angle between a beam and a wall's normal at which consecutive returns still count as one
        wall (degrees); at 75 degrees the returns are 3.9 times farther apart than face on.
    coarse_m, fine_m : float
        How far ICP looks for a return's counterpart (m) in its first two stages (the third uses
        ``inlier_m``): about a third of a place's 3 m radius, then three inlier distances.
    place_radius_m : float
        Two visits of one place stand at most this far apart (m): the reach of the search's shifts, and of
        a match's motion after ICP (an alignment farther apart is not one place).
    search_step_m : float
        Shift step of the correlative search (m), and the width of its likelihood field: half of it is
        well within ICP's first reach.
    search_step_deg : float
        Heading step of the correlative search (degrees): half of it turns a return 4 m away by 0.35 m.
    search_stride : int
        The search uses every this-many-th return of ``b`` (45 of 180 beams: 4 degrees apart).
    refine : int
        How many of the search's best candidates ICP refines.
    max_iterations : int
        ICP iterations per stage.
    n_jobs : int
        Processes for :meth:`scores` (1: this one).
    shortlist : int or None
        In :meth:`scores`, align and score in full only each image's ``shortlist`` most alike others by the
        correlative search alone (its best fit, a tenth of the cost of a match), as place recognition
        verifies its retrieved candidates geometrically; every other pair scores 0, not verified. None:
        every pair in full.
    fov_deg : float
        The field of view the images' beams cover (degrees, :func:`bootmap.surfaces.beam_angles`): 180, a
        laser's, or 360 for images all round (a place's local map, :mod:`bootmap.ingest.local_maps`).

    Examples
    --------
    >>> import numpy as np
    >>> images = np.full((3, 180), 20.0); images[0, 30:150] = 3.0; images[1, 30:150] = 3.0
    >>> ScanMatcher().scores(images).round(2)[0].tolist()
    [1.0, 1.0, 0.0]
    """

    def __init__(self, max_range: float = 20.0, inlier_m: float = 0.10, resolution_m: float = 0.05,
                 max_incidence_deg: float = 75.0, coarse_m: float = 1.0, fine_m: float = 0.30,
                 place_radius_m: float = 3.0, search_step_m: float = 0.5, search_step_deg: float = 10.0,
                 search_stride: int = 4, refine: int = 3, max_iterations: int = 30, n_jobs: int = 1,
                 fov_deg: float = 180.0, shortlist: int | None = None):
        self.max_range = max_range
        self.inlier_m = inlier_m
        self.resolution_m = resolution_m
        self.max_incidence_deg = max_incidence_deg
        self.coarse_m = coarse_m
        self.fine_m = fine_m
        self.place_radius_m = place_radius_m
        self.search_step_m = search_step_m
        self.search_step_deg = search_step_deg
        self.search_stride = search_stride
        self.refine = refine
        self.max_iterations = max_iterations
        self.n_jobs = n_jobs
        self.fov_deg = fov_deg
        self.shortlist = shortlist

    def prepare(self, image) -> _Scan:
        """An image made ready for matching (its returns, surface and k-d tree), to match many times."""
        return _Scan(image, self)

    def match(self, image_a, image_b) -> Match:
        """The best alignment of ``image_b`` onto ``image_a`` and its score.

        Parameters
        ----------
        image_a, image_b : array-like of shape (n_beams,)
            Laser images: ranges (m) from -90 to +90 degrees, ``max_range`` where nothing was seen.

        Returns
        -------
        Match
        """
        a, b = np.asarray(image_a, dtype=float).ravel(), np.asarray(image_b, dtype=float).ravel()
        if _canonical_first(b, a):
            m = self._match(self.prepare(b), self.prepare(a))
            return Match(m.score, _inverse(m.transform), m.inliers[::-1], m.points[::-1], m.refuted[::-1])
        return self._match(self.prepare(a), self.prepare(b))

    def match_prepared(self, a: _Scan, b: _Scan, start: tuple[float, float, float] | None = None) -> Match:
        """:meth:`match` of two images already :meth:`prepare`-d (``b`` onto ``a``, in that order), to match
        each many times. Given ``start`` (``b``'s pose in ``a``'s frame, as :attr:`Match.transform`), ICP
        refines that motion alone, with no search: where another source (odometry, an earlier match) says
        how the two visits lie."""
        return self._match(a, b, None if start is None else [se2(*start)])

    def _search(self, a: _Scan, b: _Scan) -> tuple[float, list[np.ndarray]]:
        """The correlative search of ``b``'s (thinned) returns over ``a``'s likelihood field, every
        ``search_step_deg`` of heading and every ``search_step_m`` of shift within a place's radius: its best
        fit as a share of those returns (in [0, 1]; 0 when either scan saw nothing), and the ``refine`` best
        candidate motions, best first."""
        if len(a.points) == 0 or len(b.points) == 0 or a.surface_tree is None or b.surface_tree is None:
            return 0.0, []
        rot = np.radians(np.arange(0.0, 360.0, self.search_step_deg))
        c, s_ = np.cos(rot), np.sin(rot)
        turned = np.stack([c[:, None] * b.sparse[:, 0] - s_[:, None] * b.sparse[:, 1],
                           s_[:, None] * b.sparse[:, 0] + c[:, None] * b.sparse[:, 1]], axis=-1)  # (R, P, 2)
        k = int(self.place_radius_m // self.search_step_m)
        g = np.arange(-k, k + 1) * self.search_step_m
        shifts = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
        shifts = shifts[np.hypot(shifts[:, 0], shifts[:, 1]) <= self.place_radius_m + 1e-9]  # (S, 2)
        fit = a.correlate(turned, shifts)  # (R, S)
        top = np.argsort(fit, axis=None)[::-1][:self.refine]
        coarse = [se2(*shifts[j], rot[i]) for i, j in zip(*np.unravel_index(top, fit.shape))]
        return float(fit.flat[top[0]]) / len(b.sparse), coarse

    def _match(self, a: _Scan, b: _Scan, coarse: list[np.ndarray] | None = None) -> Match:
        """Align ``b``'s returns onto ``a``'s surface from the search's best candidates (:meth:`_search`,
        run here unless its ``coarse`` candidates are given), each refined by ICP; the best by the
        symmetric score."""
        import small_gicp

        na, nb = len(a.points), len(b.points)
        if coarse is None:
            _, coarse = self._search(a, b)
        if not coarse:
            return Match(0.0, (0.0, 0.0, 0.0), (0, 0), (na, nb))
        best = None
        source = small_gicp.PointCloud(b.points3)
        for T in coarse:
            for reach in (self.coarse_m, self.fine_m, self.inlier_m):
                T = small_gicp.align(a.surface_cloud, source, a.surface_tree, init_T_target_source=T,
                                     registration_type="ICP", max_correspondence_distance=reach,
                                     max_iterations=self.max_iterations).T_target_source
            if math.hypot(T[0, 3], T[1, 3]) > self.place_radius_m:
                continue  # aligned only farther apart than a place's radius: not a match of one place
            Ti = np.linalg.inv(T)
            exp_b, ref_b = a.judge(b.points3 @ T[:3, :3].T + T[:3, 3], self.inlier_m)
            exp_a, ref_a = b.judge(a.points3 @ Ti[:3, :3].T + Ti[:3, 3], self.inlier_m)
            net = max(0, exp_a + exp_b - ref_a - ref_b) / (na + nb)
            if best is None or net > best[0]:
                best = (net, T, (exp_a, exp_b), (ref_a, ref_b))
        if best is None:
            return Match(0.0, (0.0, 0.0, 0.0), (0, 0), (na, nb))
        net, T, explained, refuted = best
        return Match(net, planar(T), explained, (na, nb), refuted)

    def scores(self, images, allowed=None) -> np.ndarray:
        """Scores of all pairs of images (of the shortlisted pairs, with ``shortlist``).

        Parameters
        ----------
        images : array-like of shape (n_images, n_beams)
        allowed : array-like of shape (n_images, n_images) of bool, optional
            Only the pairs ``i, j`` with ``allowed[i, j]`` or ``allowed[j, i]`` are searched and scored
            (and shortlisted among themselves), e.g. those odometry allows to be one place
            (:func:`bootmap.experiments.evaluate.within_reach`); the others score 0. Every pair when None.

        Returns
        -------
        ndarray of shape (n_images, n_images)
            ``scores[i, j]``: the score of :meth:`match` of images ``i`` and ``j`` (symmetric; higher is
            more alike), or 0 for a pair not allowed or not on either image's shortlist. The diagonal is 1
            where an image has returns, else 0, and means nothing.
        """
        X = np.asarray(images, dtype=float)
        if X.ndim != 2:
            raise ValueError(f"images must be a 2-D array (n_images, n_beams), got shape {X.shape}")
        n = len(X)
        if allowed is None:
            pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
        else:
            allowed = np.asarray(allowed, dtype=bool)
            if allowed.shape != (n, n):
                raise ValueError(f"allowed has shape {allowed.shape}, for {n} images it must be ({n}, {n})")
            i, j = np.nonzero(np.triu(allowed | allowed.T, 1))
            pairs = list(zip(i.tolist(), j.tolist()))
        coarse = None  # each pair's candidate motions, where the shortlist's search found them
        if self.shortlist is not None and self.shortlist < n - 1:
            pairs, coarse = self._shortlisted(X, pairs)
        S = np.zeros((n, n))
        if pairs:
            i, j = np.array(pairs).T
            S[i, j] = S[j, i] = self._in_parallel(_pair_scores, X, pairs, coarse)
        S[np.diag_indices(n)] = [1.0 if len(image_points(x, self.max_range, self.fov_deg)) else 0.0 for x in X]
        return S

    def _shortlisted(self, X: np.ndarray, pairs: list[tuple[int, int]]) -> tuple[list[tuple[int, int]], list]:
        """The pairs (of ``pairs``, all pairs ``i < j``) on either image's shortlist: its ``shortlist`` best
        fits by the correlative search (ties by index), in the order of ``pairs``; and each kept pair's
        candidate motions from that search (its matching starts there, not from a second search)."""
        n = len(X)
        fits = np.full((n, n), -1.0)
        searched = self._in_parallel(_pair_searches, X, pairs)
        i, j = np.array(pairs).T
        fits[i, j] = fits[j, i] = [fit for fit, _ in searched]
        best = np.argsort(-fits, axis=1, kind="stable")[:, :self.shortlist]
        keep = np.zeros((n, n), dtype=bool)
        keep[np.arange(n)[:, None], best] = True
        keep |= keep.T
        kept = [k for k, (a, b) in enumerate(pairs) if keep[a, b]]
        return [pairs[k] for k in kept], [searched[k][1] for k in kept]

    def _in_parallel(self, work, X: np.ndarray, pairs: list[tuple[int, int]], given: list | None = None) -> list:
        """``work(self, X, pairs, given)`` (one value per pair; ``given``: something per pair, or None), in
        ``n_jobs`` processes (:func:`bootmap.proc.in_processes`)."""
        return in_processes(work, self.n_jobs, (self, X), pairs, given)


def _canonical_first(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``a`` comes before ``b`` in a fixed order of images (so a pair is matched one way only)."""
    if len(a) != len(b):
        return len(a) < len(b)
    differ = np.flatnonzero(a != b)
    return bool(len(differ)) and bool(a[differ[0]] < b[differ[0]])


def _pair_scores(matcher: ScanMatcher, X: np.ndarray, pairs: list[tuple[int, int]],
                 coarse: list | None = None) -> list[float]:
    """Scores of the given pairs of rows of ``X`` (one process's share of :meth:`ScanMatcher.scores`), from
    each pair's search candidates where given."""
    return _per_pair(matcher, X, pairs,
                     lambda a, b, k: matcher._match(a, b, None if coarse is None else coarse[k]).score)


def _pair_searches(matcher: ScanMatcher, X: np.ndarray, pairs: list[tuple[int, int]], _=None) -> list[tuple]:
    """The correlative search of each pair: its best fit and candidate motions (one process's share of the
    shortlist)."""
    return _per_pair(matcher, X, pairs, lambda a, b, k: matcher._search(a, b))


def _per_pair(matcher: ScanMatcher, X: np.ndarray, pairs: list[tuple[int, int]], value) -> list:
    """``value(a, b, k)`` of each pair ``k`` of rows of ``X``, prepared once each, in the canonical order."""
    prepared: dict[int, _Scan] = {}

    def get(i: int) -> _Scan:
        if i not in prepared:
            prepared[i] = matcher.prepare(X[i])
        return prepared[i]

    out = []
    for k, (i, j) in enumerate(pairs):
        a, b = (j, i) if _canonical_first(X[j], X[i]) else (i, j)
        out.append(value(get(a), get(b), k))
    return out
