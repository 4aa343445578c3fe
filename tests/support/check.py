"""An independent re-check of the theory: does a partition of time points into dstates satisfy the axioms?

This mirrors the rules of ``asp/causal.lp``, ``asp/topological.lp`` and ``asp/metrical.lp`` in plain
Python, without clingo, and by other means: union-find for places, a union-find with parity for paths
and their directions, fixpoint closure for the order of places along a path and for the sides of a
path. It is a test oracle for the resolver (a resolved map must pass) and a way to ask why a proposed
map is wrong: every violation is a sentence that starts with the ``%!`` label of the rule it mirrors.

Example
-------
>>> from bootmap.tableau import Tableau
>>> steps = [{"view": "A", "action": {"type": "travel", "distance_m": 1}}, {"view": "B"}]
>>> t = Tableau.from_dict({"format": "bootmap.tableau/1", "steps": steps})
>>> check_map(t, ["S0", "S1"])
[]
>>> check_map(t, ["S0", "S0"])[0]
"one_value_per_feature: S0 shows view 'A' (t0) and view 'B' (t1)"
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from typing import Hashable, Iterable, Sequence

from bootmap.mapping.facts import passes_through
from bootmap.mapping.motion import quantise
from bootmap.mapping.vocabulary import QUANTUM_DEG
from bootmap.tableau import Tableau, Travel, Turn

LEVELS = ("causal", "topological", "metrical")
TRAVEL = "travel"
AROUND = 180


def true_partition(tableau: Tableau) -> list[str]:
    """The true dstate of each time point, from the tableau's ``truth`` field (as strings)."""
    out = []
    for t, step in enumerate(tableau.steps):
        if step.truth is None:
            raise ValueError(f"steps[{t}] has no truth field")
        out.append(str(step.truth))
    return out


def check_map(tableau: Tableau, dstate_of: Sequence[Hashable],
              levels: Iterable[str] = LEVELS, quantum_deg: float = QUANTUM_DEG,
              keep: Sequence[int] | None = None) -> list[str]:
    """Every violation of the axioms by the partition ``dstate_of`` of the tableau's time points.

    Parameters
    ----------
    tableau : Tableau
        Needs a view on every step.
    dstate_of : sequence
        The dstate of each time point (any hashable names, e.g. ``CognitiveMap.dstate_of``); with
        ``keep``, of each kept time point, in order.
    levels : iterable of str
        Which levels' axioms to check; ``causal`` is always checked (it defines dstates).
    quantum_deg : float
        Turn angles and heading changes are rounded to this quantum, as the resolver rounds them.
    keep : sequence of int, optional
        Check an excerpt, as an explanation states its evidence: only these time points, the actions
        between two consecutive kept ones, and headings counted afresh after every gap (the ``resume``
        frames of metrical.lp).

    Returns
    -------
    list of str
        Human-readable violations, each starting with the name of the rule it breaks; empty when the
        partition satisfies every axiom of the chosen levels.
    """
    levels = set(levels) | {"causal"}
    unknown = levels - set(LEVELS)
    if unknown:
        raise ValueError(f"unknown level(s) {sorted(unknown)}; expected some of {LEVELS}")
    times = list(range(len(tableau))) if keep is None else sorted(keep)
    if len(dstate_of) != len(times):
        raise ValueError(f"{len(dstate_of)} dstates for {len(times)} time points")
    tableau.require_views()
    exp = Experience.build(tableau, [str(d) for d in dstate_of], quantum_deg, times)
    out = _one_view(exp) + _deterministic(exp)
    if "metrical" in levels:
        out += _one_heading(exp) + ([] if exp.passes_through else _one_length(exp))
    if "topological" in levels:
        out += Topology.build(exp).violations()
    return out


# -- the causal level -------------------------------------------------------------------------------

@dataclass
class Experience:
    """The tableau (or an excerpt of it) seen through a partition: each kept time point's dstate, view
    and action, and the experienced transitions ``(dstate, action) -> {dstates}`` (``next/3`` in
    causal.lp). Lists are aligned with ``times``; the action of a time point whose successor is not
    kept is None."""

    times: list[int]
    dstate_of: list[str]
    views: list[str]
    actions: list[object]               # "travel" or a quantised turn angle (int), or None
    changes: list[int | None]           # quantised heading change of each action
    lengths: list[int | None]           # a kept travel's length in decimetres, else None
    passes_through: bool = False        # a log: travels are named by their length, which is no feature
    next: dict[tuple[str, object], dict[str, int]] = field(default_factory=dict)

    @classmethod
    def build(cls, tableau: Tableau, dstate_of: list[str], quantum_deg: float,
              times: Sequence[int] | None = None) -> "Experience":
        times = list(range(len(tableau))) if times is None else list(times)
        kept = set(times)
        steps = [tableau.steps[t] for t in times]
        linked = [s.action if t + 1 in kept else None for t, s in zip(times, steps)]
        changes = [None if a is None else _heading_change(a, quantum_deg) for a in linked]
        # A turn is named by its quantised angle (which is also its heading change), a travel by "travel"
        # (where the robot drove through dstates, by ("travel", its length in decimetres), and where such a
        # travel bent round a corner, by ("travel", its length, its heading change)).
        lengths = [round(a.distance_m * 10) if isinstance(a, Travel) else None for a in linked]
        passing = passes_through(tableau)
        actions = [None if a is None else c if isinstance(a, Turn) else TRAVEL if not passing
                   else (TRAVEL, n) if c == 0 else (TRAVEL, n, c) for a, c, n in zip(linked, changes, lengths)]
        exp = cls(times, dstate_of, [s.view for s in steps], actions, changes, lengths,   # type: ignore[arg-type]
                  passing)
        for i, a in enumerate(actions):
            if a is not None:
                # Remember the first time each transition was made, to cite it.
                exp.next.setdefault((dstate_of[i], a), {}).setdefault(dstate_of[i + 1], times[i])
        return exp

    @property
    def dstates(self) -> list[str]:
        return sorted(set(self.dstate_of), key=_natural)

    def transitions(self) -> Iterable[tuple[str, object, str]]:
        for (d, a), targets in sorted(self.next.items(), key=lambda kv: (_natural(kv[0][0]), str(kv[0][1]))):
            for d2 in sorted(targets, key=_natural):
                yield d, a, d2


def action_name(a: object) -> str:
    if isinstance(a, tuple):
        return f"travel({', '.join(map(str, a[1:]))})"
    return TRAVEL if a == TRAVEL else f"turn({a})"


def _feature_clash(exp: Experience, values: list, what: str, rule: str) -> list[str]:
    """one_value_per_feature: the first two different values a dstate shows, with their times. A value
    is a (feature, value) pair, or None where a time point does not show it; only values of one feature
    clash."""
    first: dict[tuple, dict] = defaultdict(dict)
    for t, d, value in zip(exp.times, exp.dstate_of, values):
        if value is not None:  # a time point that does not show the feature
            feature, v = value
            first[(d, feature)].setdefault(v, t)
    out = []
    for d, feature in sorted(first, key=lambda k: (_natural(k[0]), str(k[1]))):
        shown = first[(d, feature)]
        if len(shown) > 1:
            (v1, t1), (v2, t2) = sorted(shown.items(), key=lambda kv: kv[1])[:2]
            out.append(f"one_value_per_feature: {d} shows {what} {v1!r} (t{t1}) and {what} {v2!r} (t{t2})"
                       + (f" ({rule})" if rule else ""))
    return out


def _one_view(exp: Experience) -> list[str]:
    """view_is_feature + one_value_per_feature: a dstate has one view."""
    return _feature_clash(exp, [("view", v) for v in exp.views], "view", "")


def headings(exp: Experience) -> list[tuple[int, int]]:
    """heading_origin, heading_resumed, heading_after_turn, heading_after_travel: the (frame, heading)
    of every kept time point. Frame 0 starts at time 0; a run of kept time points after a gap starts a
    frame of its own, named by its first time point (headings in different frames say nothing about
    each other)."""
    out: list[tuple[int, int]] = []
    for i, t in enumerate(exp.times):
        if i == 0 or exp.actions[i - 1] is None:
            out.append((t, 0))  # the run starts a frame (frame 0 when it starts at time 0)
        else:
            frame, h = out[-1]
            out.append((frame, (h + exp.changes[i - 1]) % 360))  # type: ignore[operator]
    return out


def tableau_headings(tableau: Tableau, quantum_deg: float = QUANTUM_DEG) -> list[int]:
    """The heading of every time point as the metrical level derives it (0 at time 0)."""
    return _accumulate(_heading_change(a, quantum_deg) for a in tableau.actions)


def _heading_change(action: object, quantum_deg: float) -> int:
    """A turn's quantised angle, or a travel's quantised net heading change."""
    return quantise(action.angle_deg if isinstance(action, Turn) else action.heading_change_deg,  # type: ignore[attr-defined]
                    quantum_deg)


def _accumulate(changes: Iterable[int]) -> list[int]:
    out = [0]
    for c in changes:
        out.append((out[-1] + c) % 360)
    return out


def _one_heading(exp: Experience) -> list[str]:
    """heading_is_feature + one_value_per_feature: a dstate faces one way (metrical level), in each frame."""
    return _feature_clash(exp, headings(exp), "heading", "heading_is_feature")


def _one_length(exp: Experience) -> list[str]:
    """length_is_feature + one_value_per_feature: travelling on from a dstate covers one distance (the
    checker compares lengths to the decimetre; the resolver groups noisy ones into types first)."""
    lengths = [None if n is None else ("length", n) for n in exp.lengths]
    return _feature_clash(exp, lengths, "length (dm)", "length_is_feature")


def _deterministic(exp: Experience) -> list[str]:
    """deterministic_action: one action from one dstate reaches one dstate."""
    out = []
    for (d, a), targets in exp.next.items():
        if len(targets) > 1:
            names = sorted(targets, key=_natural)
            times = ", ".join(f"t{targets[n]}" for n in names)
            out.append(f"deterministic_action: {d} --{action_name(a)}--> {' and '.join(names)} (from {times})")
    return sorted(out)


# -- the topological level --------------------------------------------------------------------------

class UnionFind:
    """Union-find with parity: ``find(x)`` gives (root, parity of x relative to the root). Joining two
    elements with a parity that contradicts what is known marks their set as conflicting."""

    def __init__(self, items: Iterable[Hashable]):
        self.parent = {x: x for x in items}
        self.parity = {x: 0 for x in self.parent}
        self.conflict: set = set()

    def find(self, x: Hashable) -> tuple[Hashable, int]:
        p = 0
        path = []
        while self.parent[x] != x:
            path.append(x)
            p ^= self.parity[x]
            x = self.parent[x]
        root, acc = x, p
        for y in path:                      # compress: point straight at the root, keep parities right
            q = self.parity[y]
            self.parent[y], self.parity[y] = root, acc
            acc ^= q
        return root, p

    def union(self, a: Hashable, b: Hashable, parity: int = 0) -> None:
        (ra, pa), (rb, pb) = self.find(a), self.find(b)
        if ra == rb:
            if pa ^ pb != parity:
                self.conflict.add(ra)
            return
        self.parent[ra], self.parity[ra] = rb, pa ^ pb ^ parity
        if ra in self.conflict:
            self.conflict.discard(ra)
            self.conflict.add(rb)

    def root(self, x: Hashable) -> Hashable:
        return self.find(x)[0]

    def is_conflicting(self, x: Hashable) -> bool:
        return self.root(x) in self.conflict

    def groups(self) -> dict:
        out: dict = defaultdict(list)
        for x in self.parent:
            out[self.root(x)].append(x)
        return out


@dataclass
class Topology:
    """Places, paths, order and sides derived from an :class:`Experience`, as topological.lp derives them."""

    exp: Experience
    turn_links: list[tuple[str, str, int]]          # turn_link(D, D2, A), A != 180
    around: set[tuple[str, str]]                    # around(D, D2), both ways
    travel_links: list[tuple[str, str]]             # travel_link(D, D2)
    place: dict[str, str]                           # dstate -> place name
    paths: UnionFind                                # parity 0 = same direction, 1 = opposite
    ahead: dict[str, set[str]]
    behind: dict[str, set[str]]
    right: dict[str, set[str]]
    left: dict[str, set[str]]

    @classmethod
    def build(cls, exp: Experience) -> "Topology":
        turn_links, around, travel_links, bends = _links(exp)
        place = _places(exp.dstates, turn_links, around)
        paths = UnionFind(exp.dstates)
        for d, d2 in travel_links:
            paths.union(d, d2, 0)
        for d, d2 in around:
            paths.union(d, d2, 1)
        ahead, behind = _order(exp.dstates, travel_links, around, place)
        right, left = _sides(exp.dstates, turn_links, travel_links, around, ahead, bends, place)
        return cls(exp, turn_links, around, travel_links, place, paths, ahead, behind, right, left)

    def on_path(self, d: str) -> set[str]:
        """on_path(D, P): D's place and the places ahead of and behind it."""
        return {self.place[d]} | self.ahead[d] | self.behind[d]

    def path_of(self, d: str) -> set[tuple[Hashable, int]]:
        """path_of(D, Pa, Dir): one (path, direction) pair, or both directions if the path conflicts."""
        root, parity = self.paths.find(d)
        return {(root, 0), (root, 1)} if self.paths.is_conflicting(d) else {(root, parity)}

    def violations(self) -> list[str]:
        return (self._one_direction() + self._turn_leaves_path() + self._one_dstate_per_place_and_direction()
                + self._order_strict() + self._sides_ok())

    def _one_direction(self) -> list[str]:
        out = []
        for members in self.paths.groups().values():
            if self.paths.is_conflicting(members[0]):
                names = ", ".join(sorted(members, key=_natural))
                out.append(f"one_direction: the path of {{{names}}} is closed by travels and an odd number "
                           f"of turn-arounds, so its dstates face both ways along it")
        return sorted(out)

    def _turn_leaves_path(self) -> list[str]:
        return [f"turn_leaves_path: {d} --turn({a})--> {d2} stays on {d}'s path"
                for d, d2, a in self.turn_links if a != 0 and self.paths.root(d) == self.paths.root(d2)]

    def _one_dstate_per_place_and_direction(self) -> list[str]:
        at: dict[tuple, list[str]] = defaultdict(list)
        for d in self.exp.dstates:
            for pa, direction in self.path_of(d):
                at[(self.place[d], pa, direction)].append(d)
        return [f"one_dstate_per_place_and_direction: {' and '.join(ds)} are at place {self.place_text(p)} "
                f"facing the same way along the same path"
                for (p, _, _), ds in sorted(at.items(), key=lambda kv: kv[1]) if len(ds) > 1]

    def _order_strict(self) -> list[str]:
        out = []
        for d in self.exp.dstates:
            p = self.place[d]
            for rel, places in (("ahead of", self.ahead[d]), ("behind", self.behind[d])):
                if p in places:
                    out.append(f"order_irreflexive: {d}'s own place {self.place_text(p)} is {rel} it on its path")
            for q in sorted(self.ahead[d] & self.behind[d], key=_natural):
                out.append(f"order_asymmetric: place {self.place_text(q)} is both ahead of and behind {d}")
        return out

    def _sides_ok(self) -> list[str]:
        out = []
        for d in self.exp.dstates:
            on = self.on_path(d)
            for side, places in (("right", self.right[d]), ("left", self.left[d])):
                for q in sorted(places & on, key=_natural):
                    out.append(f"on_path_no_side: place {self.place_text(q)} is on {d}'s path and on its {side} "
                               f"({side}_by_turn)")
            for q in sorted(self.right[d] & self.left[d], key=_natural):
                out.append(f"one_side: place {self.place_text(q)} is both right and left of {d}'s path")
        return out

    def place_text(self, p: str) -> str:
        return "{" + ",".join(d for d in self.exp.dstates if self.place[d] == p) + "}"


def _links(exp: Experience) -> tuple[list, set, list, list]:
    """turn_link (a turn that is not a turn-around), around (both ways), travel_link and the travels that
    bent round a corner (d, d2, heading change; no travel link), from next/3."""
    turn_links, around, travel_links, bends = [], set(), [], []
    for d, a, d2 in exp.transitions():
        if isinstance(a, tuple) and len(a) == 3:
            bends.append((d, d2, a[2]))
        elif a == TRAVEL or isinstance(a, tuple):
            travel_links.append((d, d2))
        elif a == AROUND:
            around |= {(d, d2), (d2, d)}
        else:
            turn_links.append((d, d2, a))
    return turn_links, around, travel_links, bends


def _places(dstates: list[str], turn_links: list, around: set) -> dict[str, str]:
    """same_place, place_of: dstates joined by turns (of any angle) share a place, named by its first
    dstate."""
    uf = UnionFind(dstates)
    for d, d2, _ in turn_links:
        uf.union(d, d2)
    for d, d2 in around:
        uf.union(d, d2)
    return {d: min(members, key=_natural) for members in uf.groups().values() for d in members}


def _order(dstates: list[str], travel_links: list, around: set,
           place: dict[str, str]) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """order_by_travel, order_transitive, order_turn_around: the least sets ahead(D, P), behind(D, P)."""
    ahead = {d: set() for d in dstates}
    behind = {d: set() for d in dstates}
    for d, d2 in travel_links:
        ahead[d].add(place[d2])
        behind[d2].add(place[d])
    changed = True
    while changed:
        changed = False
        for d, d2 in travel_links:
            changed |= _grow(ahead[d], ahead[d2]) | _grow(behind[d2], behind[d])
        for d, d2 in around:
            changed |= _grow(ahead[d2], behind[d]) | _grow(behind[d2], ahead[d])
    return ahead, behind


def _sides(dstates: list[str], turn_links: list, travel_links: list, around: set,
           ahead: dict[str, set[str]], bends: list, place: dict[str, str]
           ) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """right_by_turn, left_by_turn, sides_by_bend, sides_along_path, sides_turn_around: the least sets
    right(D, P), left(D, P)."""
    right = {d: set() for d in dstates}
    left = {d: set() for d in dstates}
    for d, d2, a in turn_links:
        if a < 0:
            right[d] |= ahead[d2]
        elif a > 0:
            left[d] |= ahead[d2]
    for d, d2, c in bends:
        if c < 0:
            right[d].add(place[d2])
        elif c != 180:
            left[d].add(place[d2])
    changed = True
    while changed:
        changed = False
        for d, d2 in travel_links:
            for side in (right, left):
                changed |= _grow(side[d2], side[d]) | _grow(side[d], side[d2])
        for d, d2 in around:
            changed |= _grow(left[d2], right[d]) | _grow(right[d2], left[d])
    return right, left


def _grow(target: set, source: set) -> bool:
    """Add source to target; did target change?"""
    n = len(target)
    target |= source
    return len(target) != n


def _natural(name: str) -> tuple:
    """Sort S2 before S10, and truth ids like "3,1:90" sensibly."""
    head = name.rstrip("0123456789")
    tail = name[len(head):]
    return (head, int(tail) if tail else -1, name)
