"""The cognitive map: what the resolver found, named as the paper names it.

Dstates are ``S0, S1, ...``, places ``P0, ...`` and paths ``Pa0, ...``, each numbered in order of first
appearance in the tableau; a path's ``pos`` direction is the one the robot first faced along it. So
the paper's notched rectangle reads exactly like its table: S0 P0 Pa0 pos, S1 P0 Pa1 pos, ...
"""

from __future__ import annotations

from dataclasses import dataclass, field

from clingo import Symbol

from ..tableau import Tableau, Turn
from .confidence import Confidence
from .facts import length_types_of
from .motion import ActionType, LengthType
from .vocabulary import AHEAD, HEADING_OF, IS, LEFT, MISREAD, PATH_OF, PLACE_OF, RIGHT, VIEW_OF, Atoms


@dataclass(frozen=True)
class Try:
    """One grounding the resolver tried: what it asked (e.g. "at most 8 dstates") and clingo's verdict
    ("sat", "unsat" or "timeout"; "unsettled" where a search without the levels that judge the map alone
    settled nothing, its enumeration capped or no optimal map of it accepted by them, so that the same try
    was made again with them: :mod:`.mapcheck`), and the seconds its grounding and solving took."""

    dstates: str
    result: str
    seconds: float = 0.0
    #: maps the search found and the levels that judge the map alone rejected, each ruled out with every map
    #: that shares the transitions they reject it for (:meth:`.mapcheck.MapCheck.reasons`)
    rejected: int = 0


@dataclass(frozen=True)
class SolveStats:
    """How a map was found: the classes of time points, the dstates proved necessary, the groundings
    tried and the time spent grounding, solving and in all."""

    classes: int = 0
    lower_bound: int = 0
    as_seen_lower_bound: int | None = None  # dstates proved necessary reading every view as seen (misreads)
    ground_s: float = 0.0
    solve_s: float = 0.0
    total_s: float = 0.0
    bounds: tuple[Try, ...] = ()

    def to_dict(self) -> dict:
        return {"classes": self.classes, "lower_bound": self.lower_bound,
                "as_seen_lower_bound": self.as_seen_lower_bound, "ground_s": self.ground_s,
                "solve_s": self.solve_s, "total_s": self.total_s,
                "bounds": [{"dstates": b.dstates, "result": b.result, "seconds": round(b.seconds, 3),
                            "rejected": b.rejected} for b in self.bounds]}


@dataclass
class CognitiveMap:
    """A resolved map.

    Attributes
    ----------
    dstate_of : list of str
        The dstate of each time point.
    views, headings : dict
        Each dstate's view, and heading in degrees when the metrical level is on.
    place_of, path_of : dict
        Each dstate's place, and its (path, direction). Empty when the topological level is off.
    places, paths : dict
        Place -> its dstates; path -> its places in ``pos`` order.
    on, order, right_of, left_of : list of tuple
        ``(place, path)``; ``(path, before, after)`` along ``pos``; ``(place, path)`` with the
        side taken facing ``pos``.
    n_models : int
        Minimal maps found (up to the cap); ``unique`` is True when exactly one exists.
    minimal : bool
        False for a fall-back map returned on time-out: valid, but not proved minimal.
    alternatives : list of list of str
        The dstate of each time point in the other minimal maps.
    action_types : list of ActionType
        The robot's action types the axioms saw (learned, or the measurements rounded to a quantum), each
        with the resolution its kind's angles were recorded at and whether they were read as exact.
    length_types : list of LengthType
        The lengths of its travels (decimetres), with the resolution the distances were recorded at.
    suspect_steps : list of dict
        The time points whose views the map takes as misreads: ``t``, the view ``observed``, the view
        its dstate shows (``expected``) and what calling it a misread cost (a dstate costs 4).
    found_by : str
        ``"fewest dstates"`` (the paper's minimal map, :class:`~.resolver.Resolver`) or ``"loop closing"``
        (odometry's merges that every axiom accepts, :class:`~.loops.LoopCloser`; never proved minimal).
    retyped_steps : list of dict
        The actions the map takes as mistyped (:func:`~bootmap.mapping.motion.type_suspects`): ``t``,
        ``kind``, the reading (``measured_deg``), the type it was learned as (``learned_deg``), the angle
        the axioms saw instead (``abduced_deg``) and what that cost.
    stats : SolveStats
        Solver figures: classes, the bound proved, ground_s, solve_s, total_s, the groundings tried.
    confidence : Confidence or None
        What the minimal maps found agree on (:mod:`.confidence`): per dstate and place, in how many it is
        the same; the share of time points settled. None for a map not proved minimal (a fall-back on
        time-out, a loop-closed map).
    """

    steps: list[dict]
    dstate_of: list[str]
    views: dict[str, str]
    headings: dict[str, int]
    place_of: dict[str, str]
    path_of: dict[str, tuple[str, str]]
    places: dict[str, list[str]]
    paths: dict[str, list[str]]
    on: list[tuple[str, str]]
    order: list[tuple[str, str, str]]
    right_of: list[tuple[str, str]]
    left_of: list[tuple[str, str]]
    n_models: int
    unique: bool
    models_capped: bool
    alternatives: list[list[str]]
    levels: list[str]
    stats: SolveStats = field(default_factory=SolveStats)
    minimal: bool = True
    action_types: list[ActionType] = field(default_factory=list)
    length_types: list[LengthType] = field(default_factory=list)
    suspect_steps: list[dict] = field(default_factory=list)
    retyped_steps: list[dict] = field(default_factory=list)
    found_by: str = "fewest dstates"
    confidence: Confidence | None = None

    @property
    def n_dstates(self) -> int:
        return len(self.views)

    @property
    def n_places(self) -> int:
        return len(self.places)

    @property
    def n_paths(self) -> int:
        return len(self.paths)

    def same(self, a: int, b: int) -> bool:
        """Are time points a and b at the same dstate?"""
        return self.dstate_of[a] == self.dstate_of[b]

    def to_dict(self) -> dict:
        return {
            "summary": {"dstates": self.n_dstates, "places": self.n_places, "paths": self.n_paths,
                        "proved_minimal": self.minimal, "minimal_maps": self.n_models, "unique": self.unique,
                        "minimal_maps_capped": self.models_capped, "levels": self.levels,
                        "found_by": self.found_by},
            "steps": self.steps,
            "dstates": {d: {"view": self.views[d], "heading_deg": self.headings.get(d),
                            "place": self.place_of.get(d),
                            "path": self.path_of.get(d, (None, None))[0],
                            "dir": self.path_of.get(d, (None, None))[1]} for d in self.views},
            "places": self.places,
            "paths": self.paths,
            "on": [list(x) for x in self.on],
            "order": [list(x) for x in self.order],
            "right_of": [list(x) for x in self.right_of],
            "left_of": [list(x) for x in self.left_of],
            "alternatives": self.alternatives,
            "action_types": [a.to_dict() for a in self.action_types],
            "length_types": [a.to_dict() for a in self.length_types],
            "suspect_steps": self.suspect_steps,
            "retyped_steps": self.retyped_steps,
            "confidence": self.confidence.to_dict() if self.confidence is not None else None,
            "stats": self.stats.to_dict(),
        }

    def to_text(self, all_steps: bool = True) -> str:
        lines = [f"{self.n_dstates} dstates, {self.n_places} places, {self.n_paths} paths; "
                 + ("loop-closed from odometry, every axiom holds (not minimal)" if self.found_by == "loop closing"
                    else "NOT PROVED MINIMAL (time-out)" if not self.minimal else
                    "unique minimal map" if self.unique else
                    f"{self.n_models}{'+' if self.models_capped else ''} minimal maps")
                 + f"  (levels: {', '.join(self.levels)}; {self.stats.total_s:.3f} s)", ""]
        header = ("t", "view", "dstate", "place", "path", "dir", "action to next")
        rows = [(f"t{s['t']}", s["view"], s["dstate"], s["place"] or "-", s["path"] or "-",
                 s["dir"] or "-", s["action"]) for s in self.steps]
        if not all_steps and len(rows) > 20:
            rows = rows[:17] + [("...",) * 7] + rows[-2:]
        widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(7)]
        for r in [header] + rows:
            lines.append("  ".join(str(x).ljust(w) for x, w in zip(r, widths)).rstrip())
        lines.append("")
        if self.action_types:
            lines.append("action types: " + "; ".join(str(a) for a in self.action_types))
        if self.action_types or self.length_types:
            lines.append("readings: " + readings_text(self.action_types, self.length_types))
        if self.suspect_steps:
            lines.append("views taken as misreads: " + "; ".join(
                f"t{s['t']} saw {s['observed']}, its dstate shows {s['expected']}" for s in self.suspect_steps))
        if self.retyped_steps:
            lines.append("actions taken as mistyped: " + "; ".join(
                f"t{s['t']} {s['kind']} read {s['measured_deg']:+g}, typed {s['learned_deg']:+d}, taken as "
                f"{s['abduced_deg']:+d}" for s in self.retyped_steps))
        if self.confidence is not None and (self.confidence.maps > 1 or self.confidence.capped):
            lines.append(self.confidence.to_text())
        for pa, places in self.paths.items():
            lines.append(f"{pa}: {' -> '.join(places)} (pos)")
        for p, pa in self.right_of:
            lines.append(f"{p} is right of {pa} (facing pos)")
        for p, pa in self.left_of:
            lines.append(f"{p} is left of {pa} (facing pos)")
        return "\n".join(lines)


def readings_text(action_types: list[ActionType], length_types: list[LengthType]) -> str:
    """How the robot's readings were taken, kind by kind: the resolution they were recorded at, and
    whether they were read as exact primitives or as noisy readings of fewer types."""
    def one(what: str, step: float, unit: str, exact: bool) -> str:
        return f"{what} {'continuous' if step == 0 else f'to {step:g} {unit}'} ({'exact' if exact else 'noisy'})"
    kinds = {a.kind: a for a in action_types}
    out = [one(f"{kind} angles", a.resolution_deg, "deg", a.exact) for kind, a in kinds.items()]
    if length_types:
        out.append(one("distances", length_types[0].resolution_m, "m", length_types[0].exact))
    walls = {kind: (sum(a.from_walls for a in action_types if a.kind == kind),
                    sum(a.count for a in action_types if a.kind == kind)) for kind in kinds}
    if any(n for n, _ in walls.values()):
        out.append("angles read from the walls: " + ", ".join(f"{n} of {total} {kind}s"
                                                                for kind, (n, total) in walls.items()))
    return "; ".join(out)


def action_text(action) -> str:
    if action is None:
        return ""
    if isinstance(action, Turn):
        return f"turn {action.angle_deg:+g}"
    bend = f", bend {action.heading_change_deg:+g}" if action.heading_change_deg else ""
    return f"travel {action.distance_m:g} m{bend}"


def canonical_order(models: list[list[Symbol]], n: int) -> list[list[Symbol]]:
    """Minimal maps in an order that depends on the maps alone, not on how clingo found them: by their
    partitions (each time point's dstate numbered by first appearance, compared time point by time
    point), then by their atoms. The first is the map shown; the rest are its alternatives. So the same
    experience shows the same map whichever search found its minimal maps (a stream's resolve starts at
    a higher bound than a fresh one, and clingo enumerates the same maps in another order).

    >>> from clingo import Function, Number
    >>> def model(*ds):
    ...     return [Function("is", [Number(t), Function("d", [Number(d)])]) for t, d in enumerate(ds)]
    >>> [[str(a.arguments[1]) for a in m] for m in canonical_order([model(5, 7, 5), model(2, 2, 9)], 3)]
    [['d(2)', 'd(2)', 'd(9)'], ['d(5)', 'd(7)', 'd(5)']]
    """
    readings = [Reading.of_model(Atoms(m), n) for m in models]
    return [models[k] for k in _canonical(models, readings)]


@dataclass(frozen=True)
class Reading:
    """One minimal map as the cognitive map is built from it: each time point's dstate, numbered by first
    appearance (``seq``), and the atoms about its dstates (views, headings, places, paths, sides, misreads)
    whose dstate terms ``ids`` numbers. Read from a clingo model (:meth:`of_model`), or made from a
    partition kept in Python (a stream's maps, :mod:`.stream`)."""

    seq: list[int]
    ids: dict[Symbol, int]
    atoms: Atoms

    @classmethod
    def of_model(cls, atoms: Atoms, n: int) -> "Reading":
        """The reading of a model's atoms (its ``is/2`` atoms give the partition) over ``n`` time points."""
        ids, seq = _number_dstates(atoms[IS], n)
        return cls(seq, ids, atoms)


def _canonical(models: list[list[Symbol]], readings: list[Reading]) -> list[int]:
    """The indices of ``models`` (read in ``readings``) in :func:`canonical_order`: by partition, and by
    atoms only where partitions tie (a model's atoms as text cost a call each)."""
    if len(models) < 2:
        return list(range(len(models)))
    parts = [tuple(r.seq) for r in readings]
    tied = {p for p in parts if parts.count(p) > 1}
    return sorted(range(len(models)), key=lambda k: (parts[k], sorted(map(str, models[k])) if parts[k] in tied else []))


def _number_dstates(is_atoms, n: int) -> tuple[dict[Symbol, int], list[int]]:
    """Dstate terms numbered by first appearance (S0, S1, ...), and the number of each time point's.
    Clingo symbols are hashed once here: comparing them costs a C call each, so the rest uses ints."""
    term: list[Symbol] = [None] * n  # type: ignore[list-item]
    for t, d in is_atoms:
        term[t.number] = d
    ids: dict[Symbol, int] = {}
    return ids, [ids.setdefault(d, len(ids)) for d in term]


def build_map(tableau: Tableau, models: list[list[Symbol]], exhausted: bool, levels, stats: SolveStats,
              minimal: bool = True, action_types: list[ActionType] | None = None,
              misread_costs: dict[int, int] | None = None, retyped_steps: list[dict] | None = None,
              length_types: list | None = None) -> CognitiveMap:
    """The map of the first model in :func:`canonical_order`, named as the paper names it; the other models
    are alternatives.
    ``exhausted``: clingo enumerated every minimal model (so one model means a unique map);
    ``misread_costs``: what taking each suspect view as a misread cost; ``retyped_steps``: the actions
    taken as mistyped; ``length_types``: the travels' length types, when already learned
    (:func:`~bootmap.mapping.facts.length_types_of`)."""
    read: dict[Symbol, tuple] | None = {} if len(models) > 1 else None  # (models share most atoms: read once)
    readings = [Reading.of_model(Atoms(m, read), len(tableau)) for m in models]
    readings = [readings[k] for k in _canonical(models, readings)]
    return map_of(tableau, readings, exhausted, levels, stats, minimal, action_types, misread_costs, retyped_steps,
                  length_types)


def map_of(tableau: Tableau, readings: list[Reading], exhausted: bool, levels, stats: SolveStats,
           minimal: bool = True, action_types: list[ActionType] | None = None,
           misread_costs: dict[int, int] | None = None, retyped_steps: list[dict] | None = None,
           length_types: list | None = None) -> CognitiveMap:
    """The map of the first of ``readings`` (in canonical order: :func:`canonical_order`), the others its
    alternatives; the rest as :func:`build_map`."""
    n = len(tableau)
    atoms, ids, seq = readings[0].atoms, readings[0].ids, readings[0].seq
    S = [f"S{i}" for i in range(len(ids))]
    views = {S[ids[d]]: v.string for d, v in atoms[VIEW_OF]}
    headings = {S[ids[d]]: h.number for d, h in atoms[HEADING_OF]}
    place_rep = {ids[d]: ids[p] for d, p in atoms[PLACE_OF]}
    path_rep = {ids[d]: (ids[pa], dr.name) for d, pa, dr in atoms[PATH_OF]}
    # Places and paths are named in order of first appearance; pos is the way the robot first faced.
    pname: dict[int, str] = {}
    paname: dict[int, str] = {}
    flip: dict[int, bool] = {}
    for i in seq:
        if i in place_rep and place_rep[i] not in pname:
            pname[place_rep[i]] = f"P{len(pname)}"
        if i in path_rep and path_rep[i][0] not in paname:
            paname[path_rep[i][0]] = f"Pa{len(paname)}"
            flip[path_rep[i][0]] = path_rep[i][1] == "neg"
    other = {"pos": "neg", "neg": "pos"}
    place_of = {S[i]: pname[p] for i, p in place_rep.items()}
    path_of = {S[i]: (paname[pa], other[dr] if flip[pa] else dr) for i, (pa, dr) in path_rep.items()}
    places: dict[str, list[str]] = {p: [] for p in sorted(pname.values(), key=_natural1)}
    for d in sorted(place_of, key=_natural1):
        places[place_of[d]].append(d)
    # The theory derives, per dstate D, the places ahead of it and on either side of the path it faces;
    # here they are named by place and path, and sides are taken facing pos.
    on = sorted({(place_of[d], path_of[d][0]) for d in place_of if d in path_of}, key=_natural)
    order = set()
    for d, p in atoms[AHEAD]:
        pa, dr = path_of[S[ids[d]]]
        here, there = place_of[S[ids[d]]], pname[ids[p]]
        order.add((pa, here, there) if dr == "pos" else (pa, there, here))
    sides: dict[str, set] = {"right": set(), "left": set()}
    for side, mirror, pred in (("right", "left", RIGHT), ("left", "right", LEFT)):
        for d, p in atoms[pred]:
            pa, dr = path_of[S[ids[d]]]
            sides[side if dr == "pos" else mirror].add((pname[ids[p]], pa))
    order = sorted(order, key=_natural)
    paths = {pa: _ordered_places(pa, on, order) for pa in sorted(set(paname.values()), key=_natural1)}
    steps = [step_row(t, tableau.steps[t], S[i], place_of, path_of) for t, i in enumerate(seq)]
    alternatives, alternative_places = [], []
    for other in readings[1:]:
        alt_ids, alt = other.ids, other.seq
        alternatives.append([f"S{i}" for i in alt])
        place_of_alt = {alt_ids[d]: str(p) for d, p in other.atoms[PLACE_OF]}
        alternative_places.append([place_of_alt.get(i) for i in alt])
    misread = sorted(t.number for (t,) in atoms[MISREAD])
    suspect_steps = [{"t": t, "observed": tableau.steps[t].view, "expected": views[S[seq[t]]],
                      "cost": (misread_costs or {}).get(t)} for t in misread]
    return CognitiveMap(
        suspect_steps=suspect_steps, retyped_steps=list(retyped_steps or []), steps=steps, dstate_of=[S[i] for i in seq], views=dict(sorted(views.items(), key=_natural1)),
        headings=headings, place_of=place_of, path_of=path_of, places=places, paths=paths, on=on,
        order=order, right_of=sorted(sides["right"], key=_natural), left_of=sorted(sides["left"], key=_natural),
        n_models=len(readings) if minimal else 0, unique=minimal and len(readings) == 1 and exhausted,
        models_capped=minimal and not exhausted, alternatives=alternatives, levels=list(levels),
        stats=stats, minimal=minimal, action_types=list(action_types or []),
        length_types=length_types_of(tableau) if length_types is None else list(length_types),
        confidence=Confidence.of([[S[i] for i in seq]] + alternatives,
                                 [[place_of.get(S[i]) for i in seq]] + alternative_places,
                                 capped=not exhausted) if minimal else None)


def step_row(t: int, step, dstate: str, place_of: dict, path_of: dict) -> dict:
    """A time point as the map lists it: its view, dstate, place, path and direction, and the action on."""
    pa, dr = path_of.get(dstate, (None, None))
    return {"t": t, "view": step.view, "dstate": dstate, "place": place_of.get(dstate), "path": pa, "dir": dr,
            "action": action_text(step.action)}


def _natural(t: tuple) -> tuple:
    return tuple((x.rstrip("0123456789"), int(x[len(x.rstrip("0123456789")):] or 0)) for x in t)


def _natural1(item) -> tuple:
    """Natural order of a name, or of a (name, value) item: S2 before S10."""
    return _natural((item if isinstance(item, str) else item[0],))


def _ordered_places(pa: str, on: list, order: list) -> list[str]:
    """The places on a path, sorted along pos (by how many places precede each)."""
    members = [p for p, q in on if q == pa]
    before = {p: sum(1 for q, a, b in order if q == pa and b == p) for p in members}
    return sorted(members, key=lambda p: (before[p], _natural((p,))))
