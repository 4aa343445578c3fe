"""The stock topological level (``asp/topological.lp``) read in Python: whether it rejects a map, why, and
what it shows of a map it accepts.

A search that leaves the topological level out asks it of each map it finds (:mod:`.mapcheck`). Asked by
clingo, a map costs a grounding of the level on its transitions (about 9 ms for a map of 93 dstates), and
where the rest of the theory allows a thousand maps of which the level accepts two (a 256-step exploration
of a 6x5 grid, one dstate over the last map's), the checks cost ten seconds. Read here, the same verdict
takes a fraction of a millisecond: places are the components of the turns, paths the components of the
travels and turn-arounds with the direction each dstate faces (a union-find with parity), and the order
along paths and the sides of paths are sets of places (bit sets) grown to their fixpoint, each rule of the
file one line below, named as the file names it.

What the level shows of a map it accepts is read here too (:meth:`Reader.shown`, :func:`shape`): each
dstate's place and path with its direction, the places ahead of it and on either side of its path, each
place and path named by its least dstate in clingo's order of terms, as the file's ``#min`` names them. A
stream's step that adds a transition to four minimal maps of 114 dstates took 0.16 s with each map
grounded for what the level shows, 0.035 s read here. Only the file as shipped is read (:func:`stock`, by
its digest), and only where the map says of every dstate it touches that it is one; a changed file is
asked of clingo alone. That the verdicts and what is shown agree with clingo's is tested on random maps
(``tests/mapping/test_topology.py``).

Example
-------
A corridor driven both ways, turning around at its ends: two places, one path, each dstate facing one way.
A drive that travels on along one path and comes back to where it started without turning puts that place
ahead of itself (``order_irreflexive``).

>>> from clingo import Function, Number
>>> d = [Function("d", [Number(i)]) for i in range(4)]
>>> def nxt(a, action, b): return Function("next", [a, action, b])
>>> travel, around = Function("travel"), Function("turn", [Number(180)])
>>> corridor = [nxt(d[0], travel, d[1]), nxt(d[1], around, d[2]), nxt(d[2], travel, d[3]), nxt(d[3], around, d[0])]
>>> rejected_rule(corridor) is None
True
>>> rejected_rule([nxt(d[0], travel, d[1]), nxt(d[1], travel, d[0])])
'order_irreflexive'
"""

from __future__ import annotations

from typing import Sequence

from clingo import Function, Number, Symbol, SymbolType

from .theory import STOCK_DIGESTS, Theory, digest

#: The file read here, by its name among the shipped axioms (:data:`.theory.STOCK_DIGESTS`).
TOPOLOGICAL_LP = "topological.lp"

# A transition as the level reads it: (from, kind, angle, to), the dstates numbered.
_TURN, _AROUND, _TRAVEL, _BEND, _OTHER = range(5)


def stock(theory: Theory, levels: Sequence[str]) -> bool:
    """Whether ``levels`` of ``theory`` are the stock topological level alone, unchanged: then its verdicts
    may be read here."""
    if tuple(levels) != ("topological",):
        return False
    path = theory.levels["topological"]
    return STOCK_DIGESTS.get(TOPOLOGICAL_LP) == digest(path)


class Reader:
    """Reads a model's shown symbols: the map's transitions as the links the level reads, its dstates, and
    the rest, remembering each symbol (the maps of one search share most of their symbols, and reading a
    symbol's parts is a call into clingo each)."""

    def __init__(self) -> None:
        self._read: dict[Symbol, tuple | str] = {}
        self._args: dict[Symbol, Symbol] = {}  # a dstate/1 atom's dstate
        self._last: tuple | None = None  # the last model split, its transitions, links, dstates and inputs

    def split(self, model: Sequence[Symbol]) -> tuple[list[Symbol], list[Symbol], list[tuple[int, int, int, int]], int]:
        """The symbols of ``model`` that are not the map's (``own``), those that are (``next/3``,
        ``dstate/1``), the transitions' links and how many dstates they touch."""
        ids: dict[Symbol, int] = {}
        own, inputs, transitions, links = [], [], [], []
        read = self._read
        for s in model:
            kind = read.get(s)
            if kind is None:  # (the map's inputs, theory.MAP_INPUTS: next/3 and dstate/1)
                name = s.name if s.type == SymbolType.Function else ""
                kind = read[s] = (_link(s) if name == "next" and s.match("next", 3) else
                                  _DSTATE if name == "dstate" and s.match("dstate", 1) else _OWN)
            if kind is _OWN:
                own.append(s)
                continue
            inputs.append(s)
            if kind is not _DSTATE:
                a, k, angle, b = kind
                transitions.append(s)
                links.append((ids.setdefault(a, len(ids)), k, angle, ids.setdefault(b, len(ids))))
        self._last = (model, transitions, links, len(ids), ids, inputs)
        return own, inputs, links, len(ids)

    def links(self, model: Sequence[Symbol]) -> tuple[list[tuple[int, int, int, int]], int]:
        """The links of the ``next/3`` atoms among ``model``, and how many dstates they touch."""
        _, _, links, n = self.split(model)
        return links, n

    def transitions(self, model: Sequence[Symbol]) -> tuple[list[Symbol], list[tuple[int, int, int, int]], int]:
        """The ``next/3`` atoms among ``model``, their links (one each, in the same order) and how many dstates
        they touch; read again only where ``model`` is not the one last split (a search asks why the level
        rejected the map it has just judged)."""
        _, transitions, links, n, _, _ = self._split_once(model)
        return transitions, links, n

    def shown(self, model: Sequence[Symbol]) -> list[Symbol] | None:
        """What the level shows of the map among ``model`` (its ``next/3`` and ``dstate/1``), as clingo would
        show it (``place_of/2``, ``path_of/3``, ``ahead/2``, ``right/2``, ``left/2``; a place or path named
        by its least dstate in clingo's order of terms), or None where the level rejects the map."""
        _, _, links, n, ids, inputs = self._split_once(model)
        found, shape = _read(links, n)
        if found is not None:
            return None
        # the links' dstates by index (ids were given in order), then those no transition touches: each a
        # place and a path of its own
        dstates = list(ids) + [d for d in dict.fromkeys(self._dstates(inputs)) if d not in ids]
        return shape.shown(dstates)

    def covers(self, model: Sequence[Symbol]) -> bool:
        """Whether ``model`` says of every dstate its transitions touch that it is one (``dstate/1``): as the
        theory's own rules do; the level derives nothing of a dstate that is not (a theory whose rule
        for ``dstate/1`` a user deleted is asked of clingo)."""
        _, _, _, _, ids, inputs = self._split_once(model)
        return len(ids) == 0 or set(ids) <= set(self._dstates(inputs))

    def _split_once(self, model: Sequence[Symbol]) -> tuple:
        """The last split (model, transitions, links, dstates, their ids, the map's inputs), split again only
        where ``model`` is not the one last split: a search asks for the verdict, what is shown and why, of
        one model after another."""
        if self._last is None or self._last[0] is not model:
            self.split(model)
        return self._last

    def _dstates(self, inputs: Sequence[Symbol]) -> list[Symbol]:
        """The dstates named by the ``dstate/1`` atoms among ``inputs``."""
        args = self._args
        out = []
        for s in inputs:
            if self._read[s] is _DSTATE:
                d = args.get(s)
                if d is None:
                    d = args[s] = s.arguments[0]
                out.append(d)
        return out


_OWN, _DSTATE = "own", "dstate"


def _link(s: Symbol) -> tuple:
    """A transition ``next(D, A, D2)`` as (D, kind, angle, D2)."""
    a, action, b = s.arguments
    name, args = action.name, action.arguments
    if name == "turn" and len(args) == 1 and args[0].type == SymbolType.Number:
        angle = args[0].number
        return (a, _AROUND, 180, b) if angle == 180 else (a, _TURN, angle, b)
    if name == "travel" and len(args) <= 1:
        return (a, _TRAVEL, 0, b)
    if name == "travel" and len(args) == 2 and args[1].type == SymbolType.Number:
        return (a, _BEND, args[1].number, b)
    return (a, _OTHER, 0, b)  # an action the level does not read (its dstates are dstates)


def read_links(transitions: Sequence[Symbol]) -> tuple[list[tuple[int, int, int, int]], int]:
    """The transitions (``next(D, A, D2)``) as numbered links, and how many dstates they touch."""
    return Reader().links(transitions)


def rejected_rule(transitions: Sequence[Symbol]) -> str | None:
    """The first rule of the stock topological level that rejects the map made of ``transitions`` (its
    dstates are theirs), or None where the level accepts it."""
    return rejected_links(*read_links(transitions))


def rejects(transitions: Sequence[Symbol]) -> bool:
    """Whether the stock topological level rejects the map made of ``transitions``."""
    return rejected_rule(transitions) is not None


class _Parity:
    """Union-find whose members carry their parity relative to their root (paths and directions)."""

    def __init__(self, n: int):
        self.parent, self.parity = list(range(n)), [0] * n

    def find(self, x: int) -> tuple[int, int]:
        parity = 0
        path = []
        while self.parent[x] != x:
            path.append(x)
            parity ^= self.parity[x]
            x = self.parent[x]
        # compress: each member on the way points at the root with its own parity
        p = parity
        for y in path:
            self.parent[y], self.parity[y], p = x, p, p ^ self.parity[y]
        return x, parity

    def union(self, a: int, b: int, odd: int) -> bool:
        """Put a and b on one path, b facing ``odd`` relative to a; False if they already face the other way."""
        ra, pa = self.find(a)
        rb, pb = self.find(b)
        if ra == rb:
            return pa ^ pb == odd
        self.parent[rb], self.parity[rb] = ra, pa ^ pb ^ odd
        return True


def rejected_links(links: list[tuple[int, int, int, int]], n: int) -> str | None:
    """The first rule of the level that rejects the map of ``links`` (:class:`Reader`) over ``n`` dstates,
    by its label in the file, or None where the level accepts the map."""
    found = violation(links, n)
    return None if found is None else found[0]


def near_first(links: list[tuple[int, int, int, int]], n: int, start: int) -> list[int]:
    """The links (their indices) in breadth-first order over the map from dstate ``start``: the links of
    ``start`` first, then those of the dstates they reach, and so on; the links no path from ``start``
    reaches follow, each part of the map in the same order from its first link's dstate. The few links a
    level rejects together lie close in the map (a place, a path): QuickXplain finds a set that lies together
    in its order with fewer checks."""
    touching: list[list[int]] = [[] for _ in range(n)]
    for i, (a, _, _, b) in enumerate(links):
        touching[a].append(i)
        if b != a:
            touching[b].append(i)
    order, placed, seen = [], [False] * len(links), [False] * n
    for first in [start] + [a for a, _, _, _ in links]:
        if seen[first]:
            continue
        queue, seen[first] = [first], True
        for d in queue:
            for i in touching[d]:
                if not placed[i]:
                    placed[i] = True
                    order.append(i)
                    a, _, _, b = links[i]
                    for e in (a, b):
                        if not seen[e]:
                            seen[e] = True
                            queue.append(e)
    return order


def violation(links: list[tuple[int, int, int, int]], n: int) -> tuple[str, int] | None:
    """The first rule of the level that rejects the map of ``links`` over ``n`` dstates, and a dstate where
    it does (its reasons lie around it), or None where the level accepts the map."""
    if 2 * len(links) < n:  # a few links of a large map (the reasons' search): their own dstates only
        ids: dict[int, int] = {}
        own = [(ids.setdefault(a, len(ids)), k, angle, ids.setdefault(b, len(ids))) for a, k, angle, b in links]
        found = _read(own, len(ids))[0]
        if found is None:
            return None
        back = {i: d for d, i in ids.items()}
        return found[0], back[found[1]]
    return _read(links, n)[0]


class _Shape:
    """An accepted map as the level reads it: each dstate's place (a root of the turns' components), its path
    and direction (:class:`_Parity`), and the places ahead of it and on either side of its path (bit sets
    over the places' roots)."""

    def __init__(self, place: list[int], paths: _Parity, ahead: list[int], right: list[int], left: list[int]):
        self.place, self.paths, self.ahead, self.right, self.left = place, paths, ahead, right, left

    def atoms(self, dstates: list[Symbol]) -> dict[str, list[tuple[Symbol, ...]]]:
        """The level's shown atoms by predicate name, as their arguments, the dstates named by ``dstates``
        (those past the links' own have no link: each is its own place and path)."""
        n, m = len(self.place), len(dstates)
        rank = [0] * m
        for r, i in enumerate(sorted(range(m), key=dstates.__getitem__)):  # (clingo's order of terms)
            rank[i] = r
        place = self.place + list(range(n, m))
        paths = [self.paths.find(d) for d in range(n)] + [(d, 0) for d in range(n, m)]
        place_rep: dict[int, int] = {}
        path_rep: dict[int, int] = {}
        for d in range(m):  # a place, a path: named by its least dstate (#min)
            for reps, key in ((place_rep, place[d]), (path_rep, paths[d][0])):
                if key not in reps or rank[d] < rank[reps[key]]:
                    reps[key] = d
        named = {r: dstates[d] for r, d in place_rep.items()}  # a place's root -> its name
        out: dict[str, list[tuple[Symbol, ...]]] = {"place_of": [], "path_of": [], "ahead": [], "right": [],
                                                    "left": []}
        for d in range(m):
            here = dstates[d]
            out["place_of"].append((here, named[place[d]]))
            root, parity = paths[d]
            rep = path_rep[root]
            out["path_of"].append((here, dstates[rep], _POS if parity == paths[rep][1] else _NEG))
            if d < n:
                for name, bits in (("ahead", self.ahead[d]), ("right", self.right[d]), ("left", self.left[d])):
                    rows = out[name]
                    while bits:
                        low = bits & -bits
                        rows.append((here, named[low.bit_length() - 1]))
                        bits ^= low
        return out

    def shown(self, dstates: list[Symbol]) -> list[Symbol]:
        """The level's shown atoms as clingo shows them (:meth:`atoms`)."""
        return [Function(name, list(args)) for name, rows in self.atoms(dstates).items() for args in rows]


def shape(links: list[tuple[int, int, int, int]], n: int) -> _Shape | None:
    """The map of ``links`` (:class:`Reader`) over ``n`` dstates as the level reads it, or None where the
    level rejects it: :meth:`_Shape.atoms` is what the level shows of it."""
    return _read(links, n)[1]


def link_kind(action: Symbol) -> tuple[int, int]:
    """An action as the level reads a transition by it: its kind and angle (the parts of a link)."""
    _, kind, angle, _ = _link(Function("next", [Number(0), action, Number(0)]))
    return kind, angle


_POS, _NEG = Function("pos"), Function("neg")


def _read(links: list[tuple[int, int, int, int]], n: int) -> tuple[tuple[str, int] | None, _Shape | None]:
    """The first rule of the level that rejects the map of ``links`` over ``n`` dstates and a dstate where it
    does, or None and the map's shape where the level accepts it."""
    # same_place: the components of the turns (turn_linked, around included)
    place = list(range(n))

    def root(x: int) -> int:
        while place[x] != x:
            place[x] = place[place[x]]
            x = place[x]
        return x

    paths = _Parity(n)
    travels, arounds, turns, bends = [], [], [], []
    for a, kind, angle, b in links:
        if kind == _TURN or kind == _AROUND:
            ra, rb = root(a), root(b)
            if ra != rb:
                place[rb] = ra
        if kind == _TRAVEL:
            travels.append((a, b))
            # same_path along a travel, facing the same way
            if not paths.union(a, b, 0):
                return ("one_direction", a), None
        elif kind == _AROUND:
            arounds.append((a, b))
            arounds.append((b, a))
            # a turn-around flips the direction
            if not paths.union(a, b, 1):
                return ("one_direction", a), None
        elif kind == _TURN:
            turns.append((a, angle, b))
        elif kind == _BEND:
            bends.append((a, angle, b))
    # turn_leaves_path: a turn that is not a turn-around (nor by 0) leaves the path
    for a, angle, b in turns:
        if angle != 0 and paths.find(a)[0] == paths.find(b)[0]:
            return ("turn_leaves_path", a), None
    # one_dstate_per_place_and_direction
    seen: set[tuple[int, int, int]] = set()
    for d in range(n):
        key = (root(d), *paths.find(d))
        if key in seen:
            return ("one_dstate_per_place_and_direction", d), None
        seen.add(key)
    # places as bits: bit[d] is d's place
    bit = [1 << root(d) for d in range(n)]
    ahead, behind = [0] * n, [0] * n
    changed = True
    while changed:  # order_by_travel, order_transitive, order_turn_around
        changed = False
        for a, b in travels:
            x = ahead[a] | bit[b] | ahead[b]
            if x != ahead[a]:
                ahead[a], changed = x, True
            y = behind[b] | bit[a] | behind[a]
            if y != behind[b]:
                behind[b], changed = y, True
        for a, b in arounds:
            x, y = ahead[b] | behind[a], behind[b] | ahead[a]
            if x != ahead[b] or y != behind[b]:
                ahead[b], behind[b], changed = x, y, True
    for d in range(n):
        if (ahead[d] | behind[d]) & bit[d]:
            return ("order_irreflexive", d), None
        if ahead[d] & behind[d]:
            return ("order_asymmetric", d), None
    right, left = [0] * n, [0] * n
    for a, angle, b in turns:  # right_by_turn, left_by_turn
        if angle < 0:
            right[a] |= ahead[b]
        elif angle > 0:
            left[a] |= ahead[b]
    for a, angle, b in bends:  # sides_by_bend
        if angle < 0:
            right[a] |= bit[b]
        elif angle > 0 and angle != 180:
            left[a] |= bit[b]
    changed = True
    while changed:  # sides_along_path, sides_turn_around
        changed = False
        for a, b in travels:
            r, l_ = right[a] | right[b], left[a] | left[b]
            if r != right[a] or r != right[b] or l_ != left[a] or l_ != left[b]:
                right[a] = right[b] = r
                left[a] = left[b] = l_
                changed = True
        for a, b in arounds:
            x, y = left[b] | right[a], right[b] | left[a]
            if x != left[b] or y != right[b]:
                left[b], right[b], changed = x, y, True
    for d in range(n):
        on_path = bit[d] | ahead[d] | behind[d]
        if (right[d] | left[d]) & on_path:
            return ("on_path_no_side", d), None
        if right[d] & left[d]:
            return ("one_side", d), None
    return None, _Shape([root(d) for d in range(n)], paths, ahead, right, left)
