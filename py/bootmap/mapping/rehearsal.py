"""Rehearsal: the actions to take next when the experience does not decide the map.

The paper's Figure 1 closes a loop: when the minimal maps disagree, "the rehearsal procedure proposes an
exploratory sequence of actions likely to produce the relevant experience" (Kuipers & Byun 1991). Each
minimal map is a *hypothesis*: it says at which of its dstates the robot is now and, for every action
already experienced from a dstate, which dstate (so which view) follows. A sequence of actions is
informative when two hypotheses predict different views along it: whatever the robot then sees refutes
at least one of them.

The plan is found by breadth-first search over the product of the hypotheses' maps: a search state is
the dstate each hypothesis puts the robot at (or "unknown", once it leaves what that hypothesis has
seen) and the pairs of hypotheses already told apart. Breadth-first, so the first plan that tells every
pair apart is a shortest one; where none does within ``max_length`` actions, the plan tells the most
pairs apart, and where no pair can be told apart by what the maps predict, the plan leads to an action
not yet taken (new experience, which the maps cannot predict). We chose a search in Python over ASP
planning because the product of a few small maps is tiny and a shortest plan needs no optimisation;
the axioms have already done their work in the hypotheses themselves.

An action is planned only where the robot can take it: from a dstate whose view it has taken it from
before (the view is what the robot sees, whatever the hypothesis).

Example
-------
>>> from bootmap.examples import notched_rectangle
>>> Rehearsal().plan(notched_rectangle(3)).to_text()
'Nothing to rehearse: the minimal map is unique.'
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from itertools import combinations

from ..tableau import Tableau
from .cogmap import CognitiveMap
from .confidence import Confidence
from .facts import action_symbols, read_actions
from .grounding import Deadline
from .resolver import Resolver
from .vocabulary import action_word

__all__ = ["Rehearsal", "Plan"]


@dataclass(frozen=True)
class _Hypothesis:
    """One minimal map, as the search reads it: dstate -> view, (dstate, action) -> next dstate."""

    dstate_of: list[str]
    views: dict[str, str]
    next: dict[tuple[str, str], str]

    @classmethod
    def of(cls, dstate_of: list[str], views: list[str], actions: list[str | None]) -> "_Hypothesis":
        shown, nxt = {}, {}
        for t, d in enumerate(dstate_of):
            shown.setdefault(d, views[t])
            if t + 1 < len(dstate_of) and actions[t] is not None:
                nxt[(d, actions[t])] = dstate_of[t + 1]
        return cls(dstate_of, shown, nxt)

    def predict(self, at: str | None, actions: list[str]) -> list[str | None]:
        """The views this hypothesis predicts along the actions (None once it cannot say)."""
        out = []
        for a in actions:
            at = self.next.get((at, a)) if at is not None else None
            out.append(self.views[at] if at is not None else None)
        return out


@dataclass
class Plan:
    """What to do next, and why.

    Attributes
    ----------
    actions : list of str
        The actions to take from where the robot is now, as the tableau names them ("turn -90", "travel").
    hypotheses : list of dict
        Per minimal map: the dstate it puts the robot at now (``at``) and the views it predicts after each
        action (``predicts``, None where it cannot say).
    separated : int
        Pairs of hypotheses whose predictions differ along the plan (of ``pairs``).
    pairs : int
        Pairs of hypotheses.
    kind : str
        ``"nothing"`` (the map is unique), ``"distinguish"`` (every pair told apart), ``"partial"`` (some
        pairs), ``"test"`` (some maps predict views where others cannot say), ``"explore"`` (no prediction differs: the plan leads to an action not yet taken there).
    settled_now, settled_after : float
        The map's confidence (:mod:`.confidence`): the share of time points every minimal map puts at one
        dstate, now, and after the plan whatever the robot sees (the maps its views leave, at worst).
    """

    actions: list[str]
    hypotheses: list[dict] = field(default_factory=list)
    separated: int = 0
    pairs: int = 0
    kind: str = "nothing"
    settled_now: float = 1.0
    settled_after: float = 1.0

    def to_dict(self) -> dict:
        return {"kind": self.kind, "actions": self.actions, "separated_pairs": self.separated,
                "pairs": self.pairs, "hypotheses": self.hypotheses, "settled_now": self.settled_now,
                "settled_after": self.settled_after}

    def to_text(self) -> str:
        if self.kind == "nothing":
            return "Nothing to rehearse: the minimal map is unique."
        n = len(self.hypotheses)
        head = {"distinguish": f"The minimal maps disagree ({n} of them). These actions tell every one apart:",
                "partial": f"The minimal maps disagree ({n} of them). These actions tell {self.separated} of "
                           f"{self.pairs} pairs apart:",
                "test": f"The minimal maps disagree ({n} of them). Along these actions some predict views "
                        "others cannot say; seeing anything else refutes them:",
                "explore": f"The minimal maps disagree ({n} of them), and nothing they predict tells them "
                           "apart. These actions lead to experience none of them has:"}[self.kind]
        lines = [head, "  " + (", ".join(self.actions) or "(none)")]
        for i, h in enumerate(self.hypotheses):
            seen = ", ".join("?" if v is None else v for v in h["predicts"])
            lines.append(f"  map {i + 1}: now at {h['at']}; predicts {seen or '-'}")
        lines.append(f"Time points at a dstate every minimal map agrees on: {100 * self.settled_now:.0f}% now, "
                     f"at least {100 * self.settled_after:.0f}% after these actions whatever is seen.")
        return "\n".join(lines)


@dataclass
class Rehearsal:
    """Plans rehearsals: the shortest actions whose outcome the minimal maps disagree on.

    Parameters
    ----------
    resolver : Resolver, optional
        Finds the minimal maps (default: ``Resolver()``).
    max_length : int
        Longest plan searched for.

    Examples
    --------
    See the module docstring.
    """

    resolver: Resolver | None = None
    max_length: int = 10

    def plan(self, tableau: Tableau, cmap: CognitiveMap | None = None, deadline: Deadline | None = None) -> Plan:
        """The plan for this tableau (its minimal maps from ``cmap`` when given, else resolved by
        ``deadline``)."""
        resolver = self.resolver or Resolver()
        cmap = cmap or resolver.resolve(tableau, deadline)
        maps = [cmap.dstate_of] + list(cmap.alternatives)
        if len(maps) == 1:
            return Plan([])
        angles, _ = read_actions(tableau, resolver.quantum_deg)
        actions = [action_word(a) if a is not None else None
                   for a in action_symbols(tableau, angles)]
        views = [s.view for s in tableau.steps]
        hyps = [_Hypothesis.of(m, views, actions) for m in maps]
        taken_at_view: dict[str, set[str]] = {}
        for t, a in enumerate(actions[:-1]):
            if a is not None:
                taken_at_view.setdefault(views[t], set()).add(a)
        words = sorted({a for a in actions if a is not None})
        plan, separated, kind = _search(hyps, words, taken_at_view, self.max_length)
        now = [h.dstate_of[-1] for h in hyps]
        predicted = [h.predict(at, plan) for h, at in zip(hyps, now)]
        return Plan(plan, [{"at": at, "predicts": p} for at, p in zip(now, predicted)],
                    separated, len(hyps) * (len(hyps) - 1) // 2, kind,
                    _settled(maps), _settled_after(maps, predicted))


def _settled(maps: list[list[str]]) -> float:
    """The share of time points every one of ``maps`` puts at one dstate (:class:`.confidence.Confidence`)."""
    return Confidence.of(maps, [], capped=False).settled


def _settled_after(maps: list[list[str]], predicted: list[list[str | None]]) -> float:
    """The settled share among the maps the plan's outcome leaves, at worst over the outcomes the maps
    predict (a map that cannot say what will be seen is left by every outcome its known views allow)."""
    outcomes = {tuple(p) for p in predicted if None not in p} or {tuple(predicted[0])}
    worst = 1.0
    for seen in outcomes:
        left = [m for m, p in zip(maps, predicted)
                if all(v is None or s is None or v == s for v, s in zip(p, seen))]
        worst = min(worst, _settled(left or maps))
    return worst


def _search(hyps: list[_Hypothesis], words: list[str], taken_at_view: dict[str, set[str]],
            max_length: int) -> tuple[list[str], int, str]:
    """Breadth-first over (where each hypothesis puts the robot, pairs told apart, pairs tested): the
    shortest plan telling every pair apart; else the shortest telling most apart; else the shortest
    *testing* most (one map predicts a view where another cannot say: any other view refutes the first);
    else the shortest to an action not yet taken (new experience)."""
    pairs = list(combinations(range(len(hyps)), 2))
    start = (tuple(h.dstate_of[-1] for h in hyps), frozenset(), frozenset())
    parent: dict = {start: None}
    queue = deque([(start, 0)])
    best, explore = start, None
    while queue:
        state, depth = queue.popleft()
        at, apart, tested = state
        if len(apart) == len(pairs):
            return _actions(parent, state), len(apart), "distinguish"
        if depth == max_length:
            continue
        for a in _feasible(hyps, at, taken_at_view, words):
            after = tuple(h.next.get((d, a)) if d is not None else None for h, d in zip(hyps, at))
            if explore is None and any(d is not None and n is None for d, n in zip(at, after)):
                explore = (state, a)  # some map has never seen this action taken here
            views = [h.views[d] if d is not None else None for h, d in zip(hyps, after)]
            nxt = (after, apart | {(i, j) for i, j in pairs if None not in (views[i], views[j])
                                   and views[i] != views[j]},
                   tested | {(i, j) for i, j in pairs if (views[i] is None) != (views[j] is None)})
            if nxt not in parent and any(d is not None for d in after):
                parent[nxt] = (state, a)
                queue.append((nxt, depth + 1))
                if (len(nxt[1]), len(nxt[2])) > (len(best[1]), len(best[2])):
                    best = nxt
    if best[1]:
        return _actions(parent, best), len(best[1]), "partial"
    if best[2]:
        return _actions(parent, best), 0, "test"
    if explore is not None:
        state, a = explore
        return _actions(parent, state) + [a], 0, "explore"
    return [], 0, "explore"


def _feasible(hyps: list[_Hypothesis], at: tuple, taken_at_view: dict[str, set[str]],
              words: list[str]) -> list[str]:
    """The actions the robot can take now: taken before from every view the hypotheses say it sees
    (any action it has taken where none can say, or it has never left such a view)."""
    seen = {h.views[d] for h, d in zip(hyps, at) if d is not None}
    known = set.intersection(*(taken_at_view.get(v, set()) for v in seen)) if seen else set()
    return sorted(known) if known else words


def _actions(parent: dict, state) -> list[str]:
    out = []
    while parent[state] is not None:
        state, a = parent[state]
        out.append(a)
    return out[::-1]
