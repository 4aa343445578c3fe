"""The cognitive map: what the resolver found, named as the paper names it.

Dstates are ``S0, S1, ...``, places ``P0, ...`` and paths ``Pa0, ...``, each numbered in order of first
appearance in the tableau; a path's ``pos`` direction is the one the robot first faced along it. So
the paper's notched rectangle reads exactly like its table: S0 P0 Pa0 pos, S1 P0 Pa1 pos, ...
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from clingo import Symbol

from .tableau import Tableau, Turn


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
    stats : dict
        Solver figures: ground_s, solve_s, total_s, the bounds tried.
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
    stats: dict[str, Any] = field(default_factory=dict)
    minimal: bool = True

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
                        "minimal_maps_capped": self.models_capped, "levels": self.levels},
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
            "stats": self.stats,
        }

    def to_text(self, all_steps: bool = True) -> str:
        lines = [f"{self.n_dstates} dstates, {self.n_places} places, {self.n_paths} paths; "
                 + ("NOT PROVED MINIMAL (time-out)" if not self.minimal else
                    "unique minimal map" if self.unique else
                    f"{self.n_models}{'+' if self.models_capped else ''} minimal maps")
                 + f"  (levels: {', '.join(self.levels)}; {self.stats.get('total_s', 0):.3f} s)", ""]
        header = ("t", "view", "dstate", "place", "path", "dir", "action to next")
        rows = [(f"t{s['t']}", s["view"], s["dstate"], s["place"] or "-", s["path"] or "-",
                 s["dir"] or "-", s["action"]) for s in self.steps]
        if not all_steps and len(rows) > 20:
            rows = rows[:17] + [("...",) * 7] + rows[-2:]
        widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(7)]
        for r in [header] + rows:
            lines.append("  ".join(str(x).ljust(w) for x, w in zip(r, widths)).rstrip())
        lines.append("")
        for pa, places in self.paths.items():
            lines.append(f"{pa}: {' -> '.join(places)} (pos)")
        for p, pa in self.right_of:
            lines.append(f"{p} is right of {pa} (facing pos)")
        for p, pa in self.left_of:
            lines.append(f"{p} is left of {pa} (facing pos)")
        return "\n".join(lines)


def action_text(action) -> str:
    if action is None:
        return ""
    if isinstance(action, Turn):
        return f"turn {action.angle_deg:+g}"
    bend = f", bend {action.heading_change_deg:+g}" if action.heading_change_deg else ""
    return f"travel {action.distance_m:g} m{bend}"


def _first_appearance(keys_in_time_order) -> dict:
    names: dict = {}
    for k in keys_in_time_order:
        if k not in names:
            names[k] = len(names)
    return names


def _args(sym: Symbol) -> list[Symbol]:
    return list(sym.arguments)


def _by_name(symbols: list[Symbol]) -> dict[str, list[list[Symbol]]]:
    out: dict[str, list[list[Symbol]]] = {}
    for s in symbols:
        out.setdefault(s.name, []).append(_args(s))
    return out


def dstate_sequence(symbols: list[Symbol], n: int) -> tuple[list[Symbol], dict[Symbol, str]]:
    """The dstate term of each time point, and the S-names by first appearance."""
    seq: list[Symbol] = [None] * n  # type: ignore[list-item]
    for s in symbols:
        if s.name == "is" and len(s.arguments) == 2:
            seq[s.arguments[0].number] = s.arguments[1]
    order = _first_appearance(seq)
    return seq, {d: f"S{i}" for d, i in order.items()}


def build_map(tableau: Tableau, models: list[list[Symbol]], exhausted: bool, theory, stats: dict,
              minimal: bool = True) -> CognitiveMap:
    n = len(tableau)
    seq, sname = dstate_sequence(models[0], n)
    atoms = _by_name(models[0])
    views = {sname[d]: v.string for d, v in atoms.get("view_of", [])}
    headings = {sname[d]: h.number for d, h in atoms.get("heading_of", [])}
    place_term = {d: p for d, p in atoms.get("place_of", [])}
    pname = {p: f"P{i}" for p, i in _first_appearance(place_term[d] for d in seq if d in place_term).items()}
    path_term = {d: (pa, dr.name) for d, pa, dr in atoms.get("path_of", [])}
    paname = {pa: f"Pa{i}" for pa, i in _first_appearance(path_term[d][0] for d in seq if d in path_term).items()}
    # pos is the direction the robot first faced along a path.
    flip = {}
    for d in seq:
        if d in path_term and path_term[d][0] not in flip:
            flip[path_term[d][0]] = path_term[d][1] == "neg"
    other = {"pos": "neg", "neg": "pos"}

    def direction(pa, dr):
        return other[dr] if flip.get(pa) else dr

    place_of = {sname[d]: pname[p] for d, p in place_term.items()}
    path_of = {sname[d]: (paname[pa], direction(pa, dr)) for d, (pa, dr) in path_term.items()}
    places: dict[str, list[str]] = {p: [] for p in sorted(pname.values(), key=lambda x: int(x[1:]))}
    for d in sorted(place_of, key=lambda x: int(x[1:])):
        places[place_of[d]].append(d)
    # The theory derives, per dstate D, the places ahead of it and on either side of the path it faces;
    # here they are named by place and path, and sides are taken facing pos.
    on = sorted({(place_of[d], path_of[d][0]) for d in place_of if d in path_of}, key=_natural)
    order = set()
    for d, p in atoms.get("ahead", []):
        pa, dr = path_of[sname[d]]
        here, there = place_of[sname[d]], pname[p]
        order.add((pa, here, there) if dr == "pos" else (pa, there, here))
    sides: dict[str, set] = {"right": set(), "left": set()}
    for side, mirror in (("right", "left"), ("left", "right")):
        for d, p in atoms.get(side, []):
            pa, dr = path_of[sname[d]]
            sides[side if dr == "pos" else mirror].add((pname[p], pa))
    order = sorted(order, key=_natural)
    paths = {pa: _ordered_places(pa, on, order) for pa in sorted(set(paname.values()), key=_natural)}
    steps = []
    for t, d in enumerate(seq):
        s = sname[d]
        pa, dr = path_of.get(s, (None, None))
        steps.append({"t": t, "view": tableau.steps[t].view, "dstate": s, "place": place_of.get(s),
                      "path": pa, "dir": dr, "action": action_text(tableau.steps[t].action)})
    alternatives = []
    for m in models[1:]:
        alt_seq, alt_names = dstate_sequence(m, n)
        alternatives.append([alt_names[d] for d in alt_seq])
    return CognitiveMap(
        steps=steps, dstate_of=[sname[d] for d in seq], views=dict(sorted(views.items(), key=_natural1)),
        headings=headings, place_of=place_of, path_of=path_of, places=places, paths=paths, on=on,
        order=order, right_of=sorted(sides["right"], key=_natural), left_of=sorted(sides["left"], key=_natural),
        n_models=len(models) if minimal else 0, unique=minimal and len(models) == 1 and exhausted,
        models_capped=minimal and not exhausted, alternatives=alternatives, levels=list(theory.levels),
        stats=stats, minimal=minimal)


def _natural(t: tuple) -> tuple:
    return tuple((x.rstrip("0123456789"), int(x[len(x.rstrip("0123456789")):] or 0)) for x in t)


def _natural1(item) -> tuple:
    return _natural((item[0],))


def _ordered_places(pa: str, on: list, order: list) -> list[str]:
    """The places on a path, sorted along pos (by how many places precede each)."""
    members = [p for p, q in on if q == pa]
    before = {p: sum(1 for q, a, b in order if q == pa and b == p) for p in members}
    return sorted(members, key=lambda p: (before[p], _natural((p,))))
