"""Where to draw a cognitive map: its places in the plane, computed from the map itself.

The viewer (``service/static/``) draws what this module computes, so the same map is drawn the same way
every time, by every browser. Three ways, tried in this order:

``metrical``
    The metrical level gives every dstate a heading (degrees, counter-clockwise, S0 facing 0). A travel
    from place a to place b, starting at heading h, bending by c degrees over a length L, moves the robot
    by the chord of that arc: length ``L * sin(c/2) / (c/2)`` in direction ``h + c/2``. Every travel of
    the tableau is one such measurement; the places' positions are the least-squares fit of all of them
    (the first place at the origin). When the measurements close (the fit's RMS residual is under
    :data:`CLOSURE_TOLERANCE` of a typical travel) that fit is the layout.
``odometry``
    When the travels do not close but the tableau's steps carry the robot's own dead-reckoned poses (a
    log), each place is drawn at the mean of its visits' odometry, turned so that the first step faces
    along x from the origin, as the map's headings count: the robot's frame, drift and all.
``graph``
    Without headings (the metrical level off), or when the loops do not close (odometry that the
    metrical level's types absorbed but the lengths did not) and the steps carry no odometry, the places
    are placed by classical multidimensional scaling of their shortest travel distances: near in travel,
    near on the page.

Dstates are drawn around their place, each in the direction of its heading (evenly spread when there
are no headings). The true trajectory, when the tableau's steps carry poses (simulated runs, real logs),
comes out in the poses' own frame, to be drawn beside the map, never on it: the map's frame is the
robot's, the poses' the world's.

Example
-------
>>> from bootmap import examples
>>> from bootmap.mapping import Deadline, Resolver
>>> tableau = examples.notched_rectangle(circuits=1)
>>> cmap = Resolver().resolve(tableau, Deadline.after(10)).to_dict()
>>> drawn = layout(cmap, tableau.to_dict())
>>> drawn["method"], {p: drawn["places"][p]["xy"] for p in ("P0", "P1", "P2", "P3")}
('metrical', {'P0': [0.0, 0.0], 'P1': [0.0, -4.0], 'P2': [-2.0, -4.0], 'P3': [-2.0, 0.0]})
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, shortest_path
from scipy.sparse.linalg import lsqr

# The metrical fit stands when its RMS residual is under this fraction of the median travel's length.
CLOSURE_TOLERANCE = 0.2
# Dstates sit this fraction of the shortest distance between two places away from their place.
DSTATE_RING = 0.22


@dataclass(frozen=True)
class Travel:
    """One travel of the tableau as a measurement between two map nodes (places, or dstates when the
    topological level is off): ``b - a`` should be ``(dx, dy)`` (None without a heading)."""

    t: int
    a: str
    b: str
    length: float
    dx: float | None
    dy: float | None


def layout(cmap: dict, tableau: dict) -> dict:
    """The drawing of a map.

    Parameters
    ----------
    cmap : dict
        The map as ``CognitiveMap.to_dict()`` (and the service's ``/map``) gives it.
    tableau : dict
        The tableau it explains (its travels' lengths and bends, its poses).

    Returns
    -------
    dict
        ``method`` ("metrical", "odometry" or "graph"), ``closure_rms_m`` (the metrical fit's RMS residual,
        None when there are no headings), ``places`` (node -> ``{"xy", "dstates"}``), ``dstates`` (-> ``{"xy",
        "place"}``), ``paths`` (-> ``{"places", "points"}``), ``trajectory`` (the poses' ``[x, y]`` per
        step that has one, else None) and ``bounds`` ``[xmin, ymin, xmax, ymax]`` of the map's points.
    """
    rows, steps = cmap["steps"], tableau["steps"]
    nodes = _nodes(cmap)
    travels = _travels(rows, steps, cmap["dstates"])
    xy, method, rms = _metrical(nodes, travels)
    if xy is None:
        xy, method = _odometry(nodes, rows, steps), "odometry"
    if xy is None:
        xy, method = _graph(nodes, travels, cmap.get("paths", {})), "graph"
    if method != "odometry":  # odometry puts every part in one frame already
        xy = _side_by_side(xy, nodes, travels)
    places = {n: {"xy": _pt(xy[i]), "dstates": members} for i, (n, members) in enumerate(nodes.items())}
    dstates = _dstate_positions(cmap["dstates"], nodes, xy)
    paths = {p: {"places": ps, "points": [places[q]["xy"] for q in ps if q in places]}
             for p, ps in cmap.get("paths", {}).items()}
    points = np.array([v["xy"] for v in places.values()] + [v["xy"] for v in dstates.values()])
    return {"method": method, "closure_rms_m": rms, "places": places, "dstates": dstates, "paths": paths,
            "trajectory": _trajectory(steps), "bounds": _pt(points.min(axis=0)) + _pt(points.max(axis=0))}


# ---------------------------------------------------------------------------------------------------

def _nodes(cmap: dict) -> dict[str, list[str]]:
    """Map nodes in order of first visit -> their dstates: places, or each dstate alone when the map has
    no places (topological level off)."""
    nodes: dict[str, list[str]] = {}
    for row in cmap["steps"]:
        node = row["place"] or row["dstate"]
        members = nodes.setdefault(node, [])
        if row["dstate"] not in members:
            members.append(row["dstate"])
    for members in nodes.values():
        members.sort(key=lambda d: int(d[1:]) if d[1:].isdigit() else 0)
    return nodes


def _travels(rows: list[dict], steps: list[dict], dstates: dict) -> list[Travel]:
    out = []
    for t in range(len(rows) - 1):
        action = steps[t].get("action") or {}
        if action.get("type") != "travel":
            continue
        a, b = rows[t]["place"] or rows[t]["dstate"], rows[t + 1]["place"] or rows[t + 1]["dstate"]
        length, bend = float(action["distance_m"]), math.radians(action.get("heading_change_deg", 0.0))
        heading = dstates[rows[t]["dstate"]].get("heading_deg")
        if heading is None:
            out.append(Travel(t, a, b, length, None, None))
            continue
        # The chord of an arc of constant curvature: shorter than the arc, halfway between the headings.
        chord = length * (math.sin(bend / 2) / (bend / 2) if bend else 1.0)
        direction = math.radians(heading) + bend / 2
        out.append(Travel(t, a, b, length, chord * math.cos(direction), chord * math.sin(direction)))
    return out


def _odometry(nodes: dict, rows: list[dict], steps: list[dict]) -> np.ndarray | None:
    """Each node at the mean odometry of its visits, in the frame of the first step (None unless every step
    has odometry)."""
    if not steps or any("odometry" not in s for s in steps):
        return None
    odometry = np.array([s["odometry"] for s in steps], dtype=float)
    x0, y0, theta0 = odometry[0]
    c, s_ = math.cos(-theta0), math.sin(-theta0)
    local = (odometry[:, :2] - (x0, y0)) @ np.array([[c, s_], [-s_, c]])
    index = {n: i for i, n in enumerate(nodes)}
    sums, counts = np.zeros((len(nodes), 2)), np.zeros(len(nodes))
    for row, point in zip(rows, local):
        i = index[row["place"] or row["dstate"]]
        sums[i] += point
        counts[i] += 1
    return sums / counts[:, None]


def _metrical(nodes: dict, travels: list[Travel]) -> tuple[np.ndarray | None, str, float | None]:
    """Least-squares positions from the travels' displacements, or None when they are missing or do not
    close. The first node of each connected part is held at the origin."""
    moves = [tr for tr in travels if tr.a != tr.b]
    if not moves or any(tr.dx is None for tr in moves):
        return None, "graph", None
    index = {n: i for i, n in enumerate(nodes)}
    rows, cols, vals = [], [], []
    for r, tr in enumerate(moves):
        rows += [r, r]
        cols += [index[tr.b], index[tr.a]]
        vals += [1.0, -1.0]
    r = len(moves)
    _, part = _parts(nodes, travels)
    for first in sorted({int(np.flatnonzero(part == p)[0]) for p in set(part.tolist())}):
        rows.append(r)
        cols.append(first)
        vals.append(1.0)
        r += 1
    a = coo_matrix((vals, (rows, cols)), shape=(r, len(nodes))).tocsr()
    target = np.zeros((r, 2))
    target[:len(moves)] = [(tr.dx, tr.dy) for tr in moves]
    xy = np.column_stack([lsqr(a, target[:, k], atol=1e-12, btol=1e-12)[0] for k in (0, 1)])
    residual = a[:len(moves)] @ xy - target[:len(moves)]
    rms = float(np.sqrt(np.mean(np.sum(residual ** 2, axis=1))))
    scale = float(np.median([tr.length for tr in moves]))
    if rms > CLOSURE_TOLERANCE * scale:
        return None, "graph", round(rms, 6)
    return xy, "metrical", round(rms, 6)


def _parts(nodes: dict, travels: list[Travel]) -> tuple[int, np.ndarray]:
    """Connected parts of the travel graph (a tableau's walk is one, unless misreads cut it)."""
    index = {n: i for i, n in enumerate(nodes)}
    moves = [tr for tr in travels if tr.a != tr.b]
    graph = coo_matrix(([1.0] * len(moves), ([index[tr.a] for tr in moves], [index[tr.b] for tr in moves])),
                       shape=(len(nodes), len(nodes)))
    return connected_components(graph, directed=False)


def _graph(nodes: dict, travels: list[Travel], paths: dict[str, list[str]]) -> np.ndarray:
    """Classical multidimensional scaling of the shortest travel distances (each connected part alone;
    :func:`_side_by_side` sets them apart). Edges: travels (their median length), and neighbours along a
    path (length 1 when no travel joins them)."""
    index = {n: i for i, n in enumerate(nodes)}
    lengths: dict[tuple[int, int], list[float]] = {}
    for tr in travels:
        if tr.a != tr.b:
            lengths.setdefault(tuple(sorted((index[tr.a], index[tr.b]))), []).append(tr.length)
    for places in paths.values():
        for p, q in zip(places, places[1:]):
            if p in index and q in index:
                lengths.setdefault(tuple(sorted((index[p], index[q]))), []).append(1.0)
    n = len(nodes)
    xy = np.zeros((n, 2))
    if not lengths:
        return xy
    i, j = zip(*lengths)
    w = [float(np.median(v)) for v in lengths.values()]
    dist = shortest_path(coo_matrix((w, (i, j)), shape=(n, n)).tocsr(), directed=False)
    count, part = connected_components(coo_matrix((w, (i, j)), shape=(n, n)), directed=False)
    for p in range(count):
        members = np.flatnonzero(part == p)
        xy[members] = _mds(dist[np.ix_(members, members)])
    return xy


def _mds(dist: np.ndarray) -> np.ndarray:
    """Classical MDS to 2-D; each axis's sign fixed so that the result is the same on every run."""
    n = len(dist)
    if n == 1:
        return np.zeros((1, 2))
    centre = np.eye(n) - 1.0 / n
    gram = -0.5 * centre @ (dist ** 2) @ centre
    values, vectors = np.linalg.eigh(gram)
    top = np.argsort(values)[::-1][:2]
    xy = vectors[:, top] * np.sqrt(np.clip(values[top], 0, None))
    if xy.shape[1] < 2:
        xy = np.column_stack([xy, np.zeros(n)])
    for k in (0, 1):  # an eigenvector's sign is arbitrary: make the first node's coordinate non-positive
        big = np.flatnonzero(np.abs(xy[:, k]) > 1e-9)
        if big.size and xy[big[0], k] > 0:
            xy[:, k] = -xy[:, k]
    return xy - xy[0]


def _side_by_side(xy: np.ndarray, nodes: dict, travels: list[Travel]) -> np.ndarray:
    """Connected parts laid out each in its own frame are set in a row, left to right, a gap apart."""
    count, part = _parts(nodes, travels)
    if count < 2:
        return xy
    xy, right = xy.copy(), None
    for p in range(count):
        members = np.flatnonzero(part == p)
        lo, hi = xy[members].min(axis=0), xy[members].max(axis=0)
        gap = max(1.0, 0.2 * float(max(hi - lo)))
        shift = np.array([0.0 if right is None else right + gap - lo[0], -lo[1]])
        xy[members] += shift
        right = float(xy[members][:, 0].max())
    return xy


def _dstate_positions(dstates: dict, nodes: dict, xy: np.ndarray) -> dict:
    """Each dstate a little way from its place, towards its heading."""
    if len(xy) > 1:
        gaps = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2)
        gaps[gaps < 1e-9] = np.inf
        ring = DSTATE_RING * float(gaps.min()) if np.isfinite(gaps.min()) else DSTATE_RING
    else:
        ring = DSTATE_RING
    out = {}
    for i, (node, members) in enumerate(nodes.items()):
        for k, d in enumerate(members):
            heading = dstates[d].get("heading_deg")
            angle = math.radians(heading) if heading is not None else 2 * math.pi * k / len(members)
            if len(members) == 1 and heading is None:
                offset = (0.0, 0.0)
            else:
                offset = (ring * math.cos(angle), ring * math.sin(angle))
            out[d] = {"xy": _pt(xy[i] + offset), "place": node if node != d else None}
    return out


def _trajectory(steps: list[dict]) -> list[list[float]] | None:
    points = [_pt(s["pose"][:2]) for s in steps if "pose" in s]
    return points or None


def _pt(p) -> list[float]:
    return [round(float(p[0]), 4) + 0.0, round(float(p[1]), 4) + 0.0]  # + 0.0: no -0.0 in the JSON
