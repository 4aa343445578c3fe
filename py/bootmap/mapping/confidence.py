"""How sure a map is: what the minimal maps found all agree on.

The experience may leave several maps with the fewest dstates (the paper's rehearsal is for telling them
apart). A dstate of the map is *settled* when every minimal map found has a dstate with exactly its time
points; otherwise the time points it could still share a dstate with are those some other minimal map
puts with any of its own. Places likewise, through the time points at them. The whole map's figures: how
many minimal maps were found (``capped`` when the enumeration stopped at its cap, so more may exist and
"settled" means settled among those found), and the share of time points whose dstate is settled.

A unique map is settled throughout. A loop-closed map (one partition odometry proposed and the axioms
accepted, never proved minimal) has no such alternatives: it gets no confidence.

Example
-------
>>> c = Confidence.of([["S0", "S1", "S0", "S2", "S0"], ["S0", "S1", "S2", "S3", "S0"]],
...                   [["P0"] * 5, ["P0"] * 5], capped=False)
>>> c.maps, c.settled, c.dstates["S0"]["in_maps"], c.dstates["S0"]["confusable"], c.dstates["S1"]["in_maps"]
(2, 0.4, 1, [], 2)
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Sequence

__all__ = ["Confidence"]


@dataclass(frozen=True)
class Confidence:
    """What the minimal maps found agree on (module docstring).

    Attributes
    ----------
    maps : int
        Minimal maps found.
    capped : bool
        The enumeration stopped at its cap: more minimal maps may exist.
    settled : float
        The share of time points whose dstate holds the same time points in every minimal map found.
    dstates, places : dict
        Per dstate (place) of the first map: ``in_maps``, in how many of the minimal maps found it holds
        exactly the same time points; for a dstate, ``confusable``, the time points it could still share
        a dstate with (those another minimal map puts with any of its own).
    """

    maps: int
    capped: bool
    settled: float
    dstates: dict[str, dict] = field(default_factory=dict)
    places: dict[str, dict] = field(default_factory=dict)

    @classmethod
    def of(cls, dstates: Sequence[Sequence[str]], places: Sequence[Sequence[str | None]], capped: bool) -> "Confidence":
        """From the dstate (and place) of each time point in each minimal map, the first map's names first."""
        first = dstates[0]
        groups = _groups(first)
        counted = [(m, Counter(m)) for m in dstates]
        alike = {d: sum(_same_group(m, n, ts) for m, n in counted) for d, ts in groups.items()}
        others: dict[str, set[int]] = {d: set() for d in groups}
        for m in dstates[1:]:
            held = _groups(m)  # each of this map's dstates, its time points
            for d, ts in groups.items():
                for label in {m[t] for t in ts}:
                    others[d].update(held[label])
        confusable = {d: sorted(others[d] - set(ts)) for d, ts in groups.items()}
        settled = sum(len(ts) for d, ts in groups.items() if alike[d] == len(dstates)) / max(1, len(first))
        out_places = {}
        if places and all(p is not None for p in places[0]):
            counted = [(m, Counter(m)) for m in places]
            for p, ts in _groups(places[0]).items():
                out_places[p] = {"in_maps": sum(_same_group(m, n, ts) for m, n in counted), "of": len(places)}
        return cls(len(dstates), capped, round(settled, 4),
                   {d: {"in_maps": alike[d], "of": len(dstates), "confusable": confusable[d]} for d in groups},
                   out_places)

    @property
    def unsettled(self) -> list[str]:
        """The dstates some minimal map found groups otherwise."""
        return [d for d, c in self.dstates.items() if c["in_maps"] < self.maps]

    def to_dict(self) -> dict:
        return {"minimal_maps": self.maps, "capped": self.capped, "settled": self.settled,
                "dstates": self.dstates, "places": self.places}

    def to_text(self, at_most: int = 8) -> str:
        if self.maps == 1 and not self.capped:
            return "confidence: the map is unique: every dstate and place is settled"
        more = "+ (capped: more may exist)" if self.capped else ""
        head = (f"confidence: {self.maps}{more} minimal maps; {100 * self.settled:.0f}% of time points at a "
                f"dstate every one of them agrees on")
        loose = self.unsettled
        parts = [f"{d} in {self.dstates[d]['in_maps']} of {self.maps}"
                 + (f" (may be one with {', '.join(f't{t}' for t in self.dstates[d]['confusable'][:4])}"
                    f"{', ...' if len(self.dstates[d]['confusable']) > 4 else ''})"
                    if self.dstates[d]["confusable"] else "") for d in loose[:at_most]]
        if len(loose) > at_most:
            parts.append(f"and {len(loose) - at_most} more")
        return head + (": " + "; ".join(parts) if parts else "")


def _groups(labels: Sequence[str]) -> dict[str, list[int]]:
    out: dict[str, list[int]] = {}
    for t, x in enumerate(labels):
        out.setdefault(x, []).append(t)
    return out


def _same_group(labels: Sequence[str | None], counts: Counter, times: list[int]) -> bool:
    """Whether ``labels`` (of which ``counts`` counts each) gives exactly ``times`` one label."""
    x = labels[times[0]]
    return x is not None and counts[x] == len(times) and all(labels[t] == x for t in times)
