"""What changed between two maps of one tableau: dstates joined or split, places and paths changed.

Two maps of the same experience name their dstates independently (each in order of first appearance),
so they are compared through the time points: a dstate of the new map whose time points the old map had
at several dstates is a *join*; an old dstate whose time points the new map puts at several is a
*split*. Places and paths are compared the same way, through the time points at them. This is what a
person sees after asserting ``same(t3, t45)``: the join asked for, and every join determinism made of
what followed.

Example
-------
>>> from bootmap.mapping.cogmap import CognitiveMap
>>> def m(ds): return CognitiveMap([], ds, dict.fromkeys(ds, "A"), {}, {}, {}, {}, {}, [], [], [], [],
...                                1, True, False, [], [])
>>> MapDiff.between(m(["S0", "S1", "S2", "S1"]), m(["S0", "S1", "S0", "S1"])).joined
[{'now': 'S0', 'was': ['S0', 'S2']}]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

from .cogmap import CognitiveMap, _natural1

__all__ = ["MapDiff"]


@dataclass(frozen=True)
class MapDiff:
    """How ``after`` differs from ``before`` (two maps of one tableau).

    Attributes
    ----------
    joined, split : list of dict
        Dstates of ``after`` made of several of ``before`` (``now``, ``was``); dstates of ``before``
        whose time points ``after`` puts at several (``was``, ``now``).
    places_joined, places_split, paths_joined, paths_split : list of dict
        The same for places and for paths (empty where a map has no topological level).
    renamed : dict
        Dstates unchanged but for their name: before -> after (only those whose name changed).
    dstates, places, paths : tuple of int
        The counts before and after.
    """

    joined: list[dict] = field(default_factory=list)
    split: list[dict] = field(default_factory=list)
    places_joined: list[dict] = field(default_factory=list)
    places_split: list[dict] = field(default_factory=list)
    paths_joined: list[dict] = field(default_factory=list)
    paths_split: list[dict] = field(default_factory=list)
    renamed: dict[str, str] = field(default_factory=dict)
    dstates: tuple[int, int] = (0, 0)
    places: tuple[int, int] = (0, 0)
    paths: tuple[int, int] = (0, 0)

    @classmethod
    def between(cls, before: CognitiveMap, after: CognitiveMap) -> "MapDiff":
        if len(before.dstate_of) != len(after.dstate_of):
            raise ValueError(f"maps of different tableaux: {len(before.dstate_of)} and {len(after.dstate_of)} "
                             "time points")
        joined, split = _compare(before.dstate_of, after.dstate_of)
        place_joined, place_split = _compare(*(_per_time(m, lambda d, m=m: m.place_of.get(d)) for m in (before, after)))
        path_joined, path_split = _compare(*(_per_time(m, lambda d, m=m: m.path_of.get(d, (None,))[0])
                                             for m in (before, after)))
        involved = {x for j in joined for x in j["was"]} | {s["was"] for s in split}
        renamed = {b: a for b, a in zip(before.dstate_of, after.dstate_of) if b != a and b not in involved}
        return cls(joined, split, place_joined, place_split, path_joined, path_split,
                   dict(sorted(renamed.items(), key=_natural1)),
                   (before.n_dstates, after.n_dstates), (before.n_places, after.n_places),
                   (before.n_paths, after.n_paths))

    @property
    def changed(self) -> bool:
        """Whether the two maps group the time points differently (renaming aside)."""
        return bool(self.joined or self.split or self.places_joined or self.places_split
                    or self.paths_joined or self.paths_split)

    def to_dict(self) -> dict:
        return {"changed": self.changed, "joined": self.joined, "split": self.split,
                "places_joined": self.places_joined, "places_split": self.places_split,
                "paths_joined": self.paths_joined, "paths_split": self.paths_split, "renamed": self.renamed,
                "dstates": list(self.dstates), "places": list(self.places), "paths": list(self.paths)}

    def to_text(self) -> str:
        counts = (f"{self.dstates[0]} -> {self.dstates[1]} dstates, {self.places[0]} -> {self.places[1]} places, "
                  f"{self.paths[0]} -> {self.paths[1]} paths")
        if not self.changed:
            return f"what changed: nothing ({counts})"
        out = [f"what changed: {counts}"]
        for what, joined, split in (("dstate", self.joined, self.split), ("place", self.places_joined,
                                                                          self.places_split),
                                    ("path", self.paths_joined, self.paths_split)):
            out += [f"  {what}s {' + '.join(j['was'])} joined: now {j['now']}" for j in joined]
            out += [f"  {what} {s['was']} split: now {', '.join(s['now'])}" for s in split]
        return "\n".join(out)


def _per_time(cmap: CognitiveMap, of: Callable[[str], str | None]) -> list[str | None]:
    return [of(d) for d in cmap.dstate_of]


def _compare(before: Sequence[str | None], after: Sequence[str | None]) -> tuple[list[dict], list[dict]]:
    """Groups of ``after`` made of several of ``before``, and groups of ``before`` spread over several of
    ``after`` (time points with no group on either side are left out)."""
    was: dict[str, set[str]] = {}
    now: dict[str, set[str]] = {}
    for b, a in zip(before, after):
        if a is None or b is None:
            continue
        was.setdefault(a, set()).add(b)
        now.setdefault(b, set()).add(a)
    joined = [{"now": a, "was": sorted(bs, key=_natural1)} for a, bs in sorted(was.items(), key=_natural1)
              if len(bs) > 1]
    split = [{"was": b, "now": sorted(as_, key=_natural1)} for b, as_ in sorted(now.items(), key=_natural1)
             if len(as_) > 1]
    return joined, split
