"""Grid worlds: random, geometrically consistent environments and walks through them.

A world is a set of nodes on an integer grid joined by unit edges between 4-neighbours. The robot's
state is ``(node, heading)`` with the heading in {0, 90, 180, 270} degrees (0 = +x, counter-clockwise),
and that state *is* the true dstate: at a node the robot faces along one of the edges, like a robot
that has hill-climbed to the middle of an intersection and lined up with a corridor. Its view is what
the local geometry looks like relative to the heading: which of left, front, right and back are open,
e.g. ``"LF.B"`` (left, front, back open; right a wall). So views alias heavily, as in a real building; a
landmark letter on some nodes (``"LF.B/A"``) makes them less ambiguous.

Corridors may bend. A world may turn each node's frame by a multiple of 15 degrees (``frames``): the
node's four sides, and so the headings ``(node, heading)`` names, are then rotated by that angle in the
plane, and an edge between two nodes whose frames differ is a curved corridor. A travel along it has a
net heading change (``heading_change_deg``) of the difference of the frames, e.g. an L-shaped corridor
when one end is turned by 90. The nodes keep their order of sides, so the world is still a plane
figure with the same places, paths and sides; only the robot's heading in the plane changes, the
heading the metrical level accumulates from turns and bends.

Because the world is a real plane figure, the map made of the true states satisfies every axiom of the
theory (causal, topological, metrical): that is what makes these worlds useful test oracles.

Actions are those of the paper's tableau: turn left (+90), right (-90) or around (180) in place, and
travel one edge along the heading (``distance_m`` = the cell size, ``heading_change_deg`` the bend).
Everything random takes a ``numpy.random.Generator``; nothing uses a global RNG, so a seed gives one
world and one walk.

Example
-------
>>> w = GridWorld.from_ascii('''
... +-+-+
...   |
...   +
... ''')
>>> w.view(((1, 1), 0))            # facing +x at the T-junction: left closed, front, right, back open
'.FRB'
>>> t = walk(w, 10, np.random.default_rng(0))
>>> len(t), t.steps[0].truth is not None
(10, True)
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Iterable, Mapping, Sequence

import numpy as np

from bootmap.tableau import FORMAT, Tableau

Node = tuple[int, int]
State = tuple[Node, int]                    # (node, heading in degrees)
Edge = tuple[Node, Node]                    # always stored with the smaller node first

HEADINGS = (0, 90, 180, 270)
BEND_QUANTUM = 15                           # frames turn by multiples of the resolver's default quantum
TURN_LEFT, TURN_RIGHT, TURN_AROUND, TRAVEL = "left", "right", "around", "travel"
ACTIONS = (TURN_LEFT, TURN_RIGHT, TURN_AROUND, TRAVEL)
TURN_ANGLE = {TURN_LEFT: 90, TURN_RIGHT: -90, TURN_AROUND: 180}
_UNIT = {0: (1, 0), 90: (0, 1), 180: (-1, 0), 270: (0, -1)}
# Relative directions in the order a view names them, as offsets from the heading.
_SIDES = (("L", 90), ("F", 0), ("R", -90), ("B", 180))
_LETTERS = "ABCDEFGHIJKLMNOPQRSTUVWXYZ"


def _edge(a: Node, b: Node) -> Edge:
    return (a, b) if a <= b else (b, a)


def neighbour(node: Node, heading: int) -> Node:
    """The grid point one unit from ``node`` in direction ``heading``."""
    dx, dy = _UNIT[heading % 360]
    return (node[0] + dx, node[1] + dy)


@dataclass(frozen=True)
class GridWorld:
    """A graph world: nodes on an integer grid, unit edges, optional landmark letters.

    Build one with :meth:`from_edges`, :meth:`from_ascii` or :func:`random_world`.

    Parameters
    ----------
    nodes : frozenset of (int, int)
    edges : frozenset of ((int, int), (int, int))
        Unit edges between 4-neighbours, smaller node first.
    landmarks : mapping node -> str
        A letter seen at that node, appended to every view there.
    cell_m : float
        Length of an edge in metres (the ``distance_m`` of a travel).
    name : str
        Informational; copied into the tableau's ``world`` field.
    frames : mapping node -> int
        How far each node's frame is turned in the plane, in degrees (counter-clockwise; a multiple of
        15; 0 where missing). A travel from node a to node b bends by ``frames[b] - frames[a]``.
    """

    nodes: frozenset
    edges: frozenset
    landmarks: Mapping[Node, str] = field(default_factory=dict)
    cell_m: float = 2.0
    name: str = "gridworld"
    frames: Mapping[Node, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for a, b in self.edges:
            if a not in self.nodes or b not in self.nodes:
                raise ValueError(f"edge {a}-{b} has an end that is not a node")
            if abs(a[0] - b[0]) + abs(a[1] - b[1]) != 1:
                raise ValueError(f"edge {a}-{b} does not join 4-neighbours")
        for n in self.landmarks:
            if n not in self.nodes:
                raise ValueError(f"landmark at {n}, which is not a node")
        for n, angle in self.frames.items():
            if n not in self.nodes:
                raise ValueError(f"frame at {n}, which is not a node")
            # A bend off the quantum would be rounded by the resolver, and the true map's headings
            # would no longer add up: the world would stop being an oracle.
            if angle % BEND_QUANTUM != 0:
                raise ValueError(f"frame of {n} turned by {angle} degrees, not a multiple of {BEND_QUANTUM}")

    # -- construction -----------------------------------------------------------------------------

    @classmethod
    def from_edges(cls, edges: Iterable[tuple[Sequence[int], Sequence[int]]],
                   nodes: Iterable[Sequence[int]] = (), landmarks: Mapping | None = None,
                   cell_m: float = 2.0, name: str = "gridworld") -> "GridWorld":
        """A world from a list of edges (pairs of grid points); extra isolated ``nodes`` are allowed."""
        es = frozenset(_edge(tuple(a), tuple(b)) for a, b in edges)      # type: ignore[arg-type]
        ns = frozenset(tuple(n) for n in nodes) | frozenset(n for e in es for n in e)
        marks = {tuple(k): v for k, v in (landmarks or {}).items()}
        return cls(ns, es, marks, cell_m, name)                            # type: ignore[arg-type]

    @classmethod
    def from_ascii(cls, text: str, cell_m: float = 2.0, name: str = "gridworld") -> "GridWorld":
        """A world drawn in ASCII: nodes on even rows and columns, edges between them.

        ``+`` or ``o`` is a node, an upper-case letter a node with that landmark, ``-`` joins the nodes
        left and right of it, ``|`` the nodes above and below. The top line is the largest y, so the
        drawing looks like the plane (y up). Blank leading and trailing lines are ignored.

        >>> GridWorld.from_ascii("+-A").landmarks
        {(1, 0): 'A'}
        """
        rows = [r.rstrip() for r in text.strip("\n").splitlines()]
        top = len(rows) - 1
        nodes, edges, marks = set(), set(), {}
        for r, row in enumerate(rows):
            for c, ch in enumerate(row):
                if ch == " ":
                    continue
                x2, y2 = c, top - r                     # doubled coordinates
                if ch in "+o" or ch.isupper():
                    _require(x2 % 2 == 0 and y2 % 2 == 0, ch, r, c)
                    nodes.add((x2 // 2, y2 // 2))
                    if ch.isupper():
                        marks[(x2 // 2, y2 // 2)] = ch
                elif ch == "-":
                    _require(x2 % 2 == 1 and y2 % 2 == 0, ch, r, c)
                    edges.add(((x2 - 1) // 2, y2 // 2, (x2 + 1) // 2, y2 // 2))
                elif ch == "|":
                    _require(x2 % 2 == 0 and y2 % 2 == 1, ch, r, c)
                    edges.add((x2 // 2, (y2 - 1) // 2, x2 // 2, (y2 + 1) // 2))
                else:
                    raise ValueError(f"unexpected {ch!r} at line {r + 1}, column {c + 1}")
        pairs = [((x0, y0), (x1, y1)) for x0, y0, x1, y1 in edges]
        return cls.from_edges(pairs, nodes, marks, cell_m, name)

    # -- local geometry ---------------------------------------------------------------------------

    def is_open(self, node: Node, heading: int) -> bool:
        """Is there an edge leaving ``node`` in direction ``heading``?"""
        return _edge(node, neighbour(node, heading)) in self.edges

    def bend(self, state: State) -> int:
        """The net heading change of a travel from ``state`` (in (-180, 180]; 0 on a straight edge)."""
        node, heading = state
        return _wrap(self.frames.get(neighbour(node, heading), 0) - self.frames.get(node, 0))

    def plane_heading(self, state: State) -> int:
        """The robot's heading in the plane (0..359): ``heading`` turned by the node's frame."""
        node, heading = state
        return (heading + self.frames.get(node, 0)) % 360

    def with_frames(self, frames: Mapping[Sequence[int], int]) -> "GridWorld":
        """The same world with its nodes' frames turned (its corridors bent) as ``frames`` says.

        >>> w = GridWorld.from_ascii("+-+").with_frames({(1, 0): 90})      # an L-shaped corridor
        >>> w.bend(((0, 0), 0)), w.bend(((1, 0), 180)), w.plane_heading(((1, 0), 0))
        (90, -90, 90)
        """
        return replace(self, frames={tuple(k): int(v) for k, v in frames.items() if v % 360})  # type: ignore[misc]

    def view(self, state: State) -> str:
        """The view at a state: open sides as ``L F R B`` (``.`` for a wall), then any landmark."""
        node, heading = state
        shape = "".join(ch if self.is_open(node, heading + off) else "." for ch, off in _SIDES)
        mark = self.landmarks.get(node)
        return f"{shape}/{mark}" if mark else shape

    def actions(self, state: State) -> list[str]:
        """The actions the robot may take: a quarter turn only towards an open side, a turn-around
        always, a travel only when the front is open."""
        node, heading = state
        out = [a for a in (TURN_LEFT, TURN_RIGHT) if self.is_open(node, heading + TURN_ANGLE[a])]
        out.append(TURN_AROUND)
        if self.is_open(node, heading):
            out.append(TRAVEL)
        return out

    def step(self, state: State, action: str) -> State:
        """The state after an action (which must be allowed)."""
        node, heading = state
        if action == TRAVEL:
            if not self.is_open(node, heading):
                raise ValueError(f"cannot travel from {truth_id(state)}: the front is a wall")
            return (neighbour(node, heading), heading)
        return (node, (heading + TURN_ANGLE[action]) % 360)

    def open_headings(self, node: Node) -> list[int]:
        return [h for h in HEADINGS if self.is_open(node, h)]

    def is_connected(self) -> bool:
        """Can every node be reached from every other along edges?"""
        if not self.nodes:
            return False
        start = min(self.nodes)
        seen, todo = {start}, [start]
        while todo:
            n = todo.pop()
            for h in self.open_headings(n):
                m = neighbour(n, h)
                if m not in seen:
                    seen.add(m)
                    todo.append(m)
        return len(seen) == len(self.nodes)

    def to_ascii(self) -> str:
        """The inverse of :meth:`from_ascii` (for messages and test reports)."""
        xs = [x for x, _ in self.nodes]
        ys = [y for _, y in self.nodes]
        x0, y0 = min(xs), min(ys)
        w, h = 2 * (max(xs) - x0) + 1, 2 * (max(ys) - y0) + 1
        grid = [[" "] * w for _ in range(h)]
        for (x, y) in self.nodes:
            grid[h - 1 - 2 * (y - y0)][2 * (x - x0)] = self.landmarks.get((x, y), "+")
        for (ax, ay), (bx, by) in self.edges:
            cx, cy = ax + bx - 2 * x0, ay + by - 2 * y0
            grid[h - 1 - cy][cx] = "-" if ay == by else "|"
        return "\n".join("".join(r).rstrip() for r in grid)


def _require(ok: bool, ch: str, r: int, c: int) -> None:
    if not ok:
        raise ValueError(f"{ch!r} at line {r + 1}, column {c + 1} is off the node/edge lattice")


def _wrap(angle: int) -> int:
    """An angle in (-180, 180], as the resolver quantises heading changes."""
    a = (angle + 180) % 360 - 180
    return 180 if a == -180 else a


def truth_id(state: State) -> str:
    """The true dstate's id, e.g. ``"3,1:90"``."""
    (x, y), h = state
    return f"{x},{y}:{h}"


# -- random worlds --------------------------------------------------------------------------------

def random_world(rng: np.random.Generator, width: int, height: int, extra_edges: int = 0,
                 landmarks: float = 0.0, keep: float = 1.0, letters: str = _LETTERS,
                 cell_m: float = 2.0, bends: float = 0.0, bend_deg: int = BEND_QUANTUM) -> GridWorld:
    """A random connected world inside a ``width`` x ``height`` grid.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only source of randomness.
    width, height : int
        Grid size; at least two nodes in all.
    extra_edges : int
        Edges added to the random spanning tree (as many as there are, if fewer), making loops.
    landmarks : float
        Fraction of nodes (rounded) that carry a landmark letter.
    keep : float
        Fraction of the grid's nodes used (a random connected region grown from a random node).
    letters : str
        Landmark letters, drawn at random with replacement (few letters: landmarks alias too).
    cell_m : float
        Edge length in metres.
    bends : float
        Fraction of nodes (rounded) whose frame is turned by a random non-zero multiple of 15 degrees,
        bending every corridor between nodes whose frames differ. (Drawn last, so ``bends=0`` gives the
        same world from the same generator as before bends existed.)
    bend_deg : int
        The frames are turned by multiples of this (a multiple of 15): 45 gives a world of 45-degree
        geometry, whose corridors meet at 45, 90 and 135 degrees.
    """
    if width * height < 2:
        raise ValueError("a world needs at least two nodes")
    nodes = _grow_region(rng, width, height, max(2, round(keep * width * height)))
    candidates = sorted({_edge(n, neighbour(n, h)) for n in nodes for h in (0, 90)
                         if neighbour(n, h) in nodes})
    tree = _spanning_tree(rng, nodes, candidates)
    rest = [e for e in candidates if e not in tree]
    picks = rng.permutation(len(rest))[:max(0, extra_edges)]
    edges = tree | {rest[i] for i in picks}
    marks = _place_landmarks(rng, sorted(nodes), landmarks, letters)
    frames = _turn_frames(rng, sorted(nodes), bends, bend_deg)
    name = f"grid {width}x{height}, {len(nodes)} nodes, {len(edges)} edges"
    name += f", {len(frames)} frames turned" if frames else ""
    return GridWorld(frozenset(nodes), frozenset(edges), marks, cell_m, name, frames)


def _grow_region(rng: np.random.Generator, width: int, height: int, size: int) -> set[Node]:
    """A random connected set of ``size`` grid points, grown one frontier point at a time."""
    all_nodes = [(x, y) for x in range(width) for y in range(height)]
    region = {all_nodes[int(rng.integers(len(all_nodes)))]}
    while len(region) < min(size, len(all_nodes)):
        around = {neighbour(n, h) for n in region for h in HEADINGS}
        frontier = sorted((around & set(all_nodes)) - region)
        region.add(frontier[int(rng.integers(len(frontier)))])
    return region


def _spanning_tree(rng: np.random.Generator, nodes: set[Node], candidates: list[Edge]) -> set[Edge]:
    """Randomised Kruskal: candidate edges in random order, kept when they join two components."""
    parent = {n: n for n in nodes}

    def find(n: Node) -> Node:
        while parent[n] != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n

    tree = set()
    for i in rng.permutation(len(candidates)):
        a, b = candidates[i]
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[ra] = rb
            tree.add(candidates[i])
    return tree


def _place_landmarks(rng: np.random.Generator, nodes: list[Node], fraction: float,
                     letters: str) -> dict[Node, str]:
    count = min(len(nodes), round(fraction * len(nodes)))
    chosen = rng.permutation(len(nodes))[:count]
    return {nodes[i]: letters[int(rng.integers(len(letters)))] for i in sorted(chosen)}


def _turn_frames(rng: np.random.Generator, nodes: list[Node], fraction: float, step: int) -> dict[Node, int]:
    count = min(len(nodes), round(fraction * len(nodes)))
    if count == 0:
        return {}
    if step % BEND_QUANTUM or not 0 < step <= 180:
        raise ValueError(f"bend_deg must be a multiple of {BEND_QUANTUM} in (0, 180], got {step}")
    angles = [a for a in range(-180 + step, 181, step) if a != 0]
    chosen = rng.permutation(len(nodes))[:count]
    return {nodes[i]: angles[int(rng.integers(len(angles)))] for i in sorted(chosen)}


# -- walks ----------------------------------------------------------------------------------------

def walk(world: GridWorld, n_steps: int, rng: np.random.Generator, policy: str = "random",
         start: State | None = None) -> Tableau:
    """A walk of ``n_steps`` time points (``n_steps - 1`` actions) through ``world``, as a tableau.

    Parameters
    ----------
    policy : {"random", "explore"}
        ``random``: at each dstate an allowed action uniformly at random, but never two turns in a row
        (so the robot keeps moving). ``explore``: an action not yet tried from this state if there is
        one, else the shortest known way (through transitions already experienced) to a state that has
        one; also never two turns in a row.
    start : (node, heading), optional
        Default: a random node, facing a random open direction.

    Returns
    -------
    Tableau
        With view, action (a travel's ``heading_change_deg`` is its bend), truth (``"x,y:heading"``,
        the heading in the node's frame) and pose (metres, metres, radians in the plane) per step.
    """
    if n_steps < 1:
        raise ValueError("a walk has at least one time point")
    choose = {"random": _RandomPolicy, "explore": _ExplorePolicy}
    if policy not in choose:
        raise ValueError(f"unknown policy {policy!r}; expected one of {sorted(choose)}")
    state = start if start is not None else _random_start(world, rng)
    agent = choose[policy](world, rng)
    states, actions = [state], []
    for _ in range(n_steps - 1):
        action = agent.choose(state, actions[-1] if actions else None)
        nxt = world.step(state, action)
        agent.record(state, action, nxt)
        actions.append(action)
        states.append(nxt)
        state = nxt
    return _tableau(world, states, actions, policy)


def scripted(world: GridWorld, start: State, actions: Sequence[str]) -> Tableau:
    """The tableau of a given sequence of actions (``"travel"``, ``"left"``, ``"right"``, ``"around"``)
    from ``start`` = (node, heading): hand-made tableaux with known answers.

    >>> corridor = GridWorld.from_ascii("+-+")
    >>> [s.view for s in scripted(corridor, ((0, 0), 0), ["travel", "around"]).steps]
    ['.F..', '...B', '.F..']
    """
    states = [start]
    for action in actions:
        states.append(world.step(states[-1], action))
    return _tableau(world, states, list(actions), "scripted")


def _random_start(world: GridWorld, rng: np.random.Generator) -> State:
    starts = sorted((n, h) for n in world.nodes for h in world.open_headings(n))
    if not starts:
        raise ValueError("the world has no edges: the robot cannot move")
    return starts[int(rng.integers(len(starts)))]


def _allowed(world: GridWorld, state: State, previous: str | None) -> list[str]:
    """Allowed actions, without a second turn in a row while a travel is possible."""
    acts = world.actions(state)
    if previous is not None and previous != TRAVEL and TRAVEL in acts:
        return [TRAVEL]
    return acts


class _RandomPolicy:
    def __init__(self, world: GridWorld, rng: np.random.Generator):
        self.world, self.rng = world, rng

    def choose(self, state: State, previous: str | None) -> str:
        acts = _allowed(self.world, state, previous)
        return acts[int(self.rng.integers(len(acts)))]

    def record(self, state: State, action: str, nxt: State) -> None:
        pass


class _ExplorePolicy:
    """Systematic exploration from experience: the robot knows its state, what it sees there (which
    actions are allowed) and the transitions it has made, but nothing about unvisited parts."""

    def __init__(self, world: GridWorld, rng: np.random.Generator):
        self.world, self.rng = world, rng
        self.known: dict[tuple[State, str], State] = {}
        self.allowed_at: dict[State, list[str]] = {}
        self.plan: list[str] = []

    def record(self, state: State, action: str, nxt: State) -> None:
        self.known[(state, action)] = nxt

    def choose(self, state: State, previous: str | None) -> str:
        self.allowed_at.setdefault(state, self.world.actions(state))
        acts = _allowed(self.world, state, previous)
        untried = [a for a in acts if (state, a) not in self.known]
        if untried:
            self.plan = []
            return untried[int(self.rng.integers(len(untried)))]
        if not self.plan:
            self.plan = self._route(state, previous)
        if self.plan and self.plan[0] in acts:
            return self.plan.pop(0)
        self.plan = []
        return acts[int(self.rng.integers(len(acts)))]

    def _route(self, state: State, previous: str | None) -> list[str]:
        """Breadth-first search over experienced transitions (respecting no two turns in a row) to a
        state with an action not yet tried; [] when the known graph is fully explored."""
        turned = previous is not None and previous != TRAVEL
        start = (state, turned)
        back: dict = {start: None}
        queue = deque([start])
        while queue:
            node = queue.popleft()
            s, t = node
            if node != start and self._has_untried(s, t):
                return _unwind(back, node)
            for a in self.allowed_at.get(s, []):
                if t and a != TRAVEL and TRAVEL in self.allowed_at[s]:
                    continue
                nxt = self.known.get((s, a))
                if nxt is not None and (nxt, a != TRAVEL) not in back:
                    back[(nxt, a != TRAVEL)] = (node, a)
                    queue.append((nxt, a != TRAVEL))
        return []

    def _has_untried(self, state: State, turned: bool) -> bool:
        acts = self.allowed_at.get(state)
        if acts is None:
            return True                         # seen as a destination but never stood at: unexplored
        if turned and TRAVEL in acts:
            acts = [TRAVEL]
        return any((state, a) not in self.known for a in acts)


def _unwind(back: dict, node) -> list[str]:
    out = []
    while back[node] is not None:
        node, a = back[node]
        out.append(a)
    return out[::-1]


def _tableau(world: GridWorld, states: list[State], actions: list[str], policy: str) -> Tableau:
    steps = []
    for t, state in enumerate(states):
        (x, y), h = state
        step = {"view": world.view(state), "truth": truth_id(state),
                "pose": [x * world.cell_m, y * world.cell_m, math.radians(world.plane_heading(state))]}
        if t < len(actions):
            step["action"] = _action_dict(actions[t], world.cell_m, world.bend(state))
        steps.append(step)
    doc = {"format": FORMAT, "world": world.name, "meta": {"policy": policy, "generator": "support.gridworld"},
           "steps": steps}
    return Tableau.from_dict(doc, "gridworld walk")


def _action_dict(action: str, cell_m: float, bend: int) -> dict:
    if action == TRAVEL:
        return {"type": "travel", "distance_m": cell_m, **({"heading_change_deg": bend} if bend else {})}
    return {"type": "turn", "angle_deg": TURN_ANGLE[action]}
