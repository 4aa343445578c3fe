"""The levels that judge the map alone, asked of each map a search finds instead of searched with.

A level whose every rule reads only the map's transitions and dstates (``next/3``, ``dstate/1``;
:attr:`~.theory.Theory.map_levels`: the topological level) says the same of every time point of a
dstate: it accepts or rejects a partition of the time points as a whole, by its quotient graph. Grounded
with the search, its rules range over every pair of *candidate* dstates, most of the grounding where a
class may take several.

So where a bound leaves no spare dstate (each class takes the dstates its proved lower bound says: the
search only assigns time points to them), the search (:mod:`.search.exact`) leaves such levels out and
asks them of each map it finds, on that map's few dstates and transitions (:class:`MapCheck`): a
1,000-step walk of a 5x5 grid resolves in 0.39 s instead of 0.91 s. With spare dstates the fewest dstates
the rest of the theory allows tend to undercut what places and paths allow (views alone join what they
keep apart: on a half-explored 6x5 grid, 257 steps, every one of the eight such maps was rejected), and
the search grounds every level.

This is exact, not a heuristic: the maps of the whole theory are the maps of the rest that the left-out
levels accept, so

- where the rest has no map within a bound, neither has the whole theory (a proof of a bound is kept);
- where every map within a bound was enumerated, those the levels accept are every map of the whole
  theory within it (none: the bound is proved too small);
- optimising, where an optimal map of the rest is accepted, the accepted optimal maps are all the
  optimal maps of the whole theory.

Where none of that can be concluded (the enumeration was capped before it was complete, or no optimal map
found was accepted), the search grounds again with every level, as it always did.

A level that says it is monotone (:attr:`~.theory.Theory.monotone_levels`: a map it rejects stays rejected
with more dstates and transitions, under any names) also says why it rejects a map: the fewest of its
transitions it rejects on their own (:meth:`MapCheck.reasons`). A search then rules out every map with
those transitions, renamed any way (:mod:`.search.exact`), and may leave the level out whatever its bound:
on 2,000 steps with a person's apart, 104 dstates over a bound of 103, 2.8 s instead of 9 s.

Under the stock topological level (the file as shipped: :func:`.topology.stock`) the verdict, the reasons
and what the level shows of a map it accepts are read in Python (:mod:`.topology`): no map costs a
grounding, and no reasons a solve (QuickXplain over the Python verdict). A search then leaves the level
out and learns from the maps it rejects at any size (not only above ``LEARN_MIN_SIZE``): the slowest step
of a 2,000-step stream of a 6x5 grid, 93 dstates with a spare slot per class, 1.6 s with the level
grounded over every candidate dstate, 0.3 s learning from 11 rejected maps.
"""

from __future__ import annotations

from typing import Sequence

import clingo
from clingo import Symbol

from .facts import add_facts
from .theory import MAP_INPUTS, Theory
from .topology import Reader, near_first, stock, violation
from .vocabulary import NEXT

#: What a search without the map's levels shows beside its own atoms: the map the levels judge.
SHOW_MAP = "".join(f"#show {name}/{arity}. " for name, arity in sorted(MAP_INPUTS))

#: The check shows only what the levels ``#show`` (as beside the other files, which show atoms), not every
#: atom, as a program without any ``#show`` would.
SHOW_ONLY_SHOWN = "#show."

#: How the search's reason for a rejection is asked: each transition of the map is an external atom the
#: levels read, true only where assumed, and its dstates are dstates, so that a solve under some of them
#: asks the levels of the map made of those transitions alone (no other dstate: a reason holds of every
#: map with those transitions, whatever else it has, only where the map it names is just them).
_TRANSITION = "bootmap_map_transition"
ASK_TRANSITIONS = (f"#external next(D, A, D2) : {_TRANSITION}(D, A, D2)."
                   " dstate(D) :- next(D, _, _). dstate(D) :- next(_, _, D).")


class MapCheck:
    """Ask the levels ``levels`` of ``theory`` (each of :attr:`Theory.map_levels`) of one map at a time.

    Calling it with the shown symbols of a model found without those levels (its ``next/3`` and
    ``dstate/1`` among them) gives the model's symbols as the whole theory would show them (the map's
    transitions and dstates left out, the levels' own shown atoms added: places, paths, order and
    sides), or None when the levels reject the map.
    """

    def __init__(self, theory: Theory, levels: Sequence[str]):
        self.files = [str(theory.levels[name]) for name in levels]
        #: whether every level says it is monotone (:attr:`Theory.monotone_levels`): then :meth:`reasons`
        #: of a rejected map holds of every map that has them
        self.monotone = all(name in theory.monotone_levels for name in levels)
        #: whether the levels are the stock topological level, whose verdicts are read in Python
        #: (:mod:`.topology`): a map it rejects is not grounded, and the reasons take no solve
        self.fast = stock(theory, levels)
        self._reader = Reader()

    def _grounded(self, facts: Sequence[Symbol], program: str = "") -> clingo.Control:
        """The levels grounded on these facts (and ``program``, the project's own rules), showing only what
        they show."""
        control = clingo.Control(["--warn=none"])
        for f in self.files:
            control.load(f)
        control.add("base", [], SHOW_ONLY_SHOWN + program)
        add_facts(control, facts)
        control.ground([("base", [])])
        return control

    def _asking(self, facts: Sequence[Symbol], transitions: Sequence[Symbol]) -> tuple[clingo.Control, list[int]]:
        """The levels grounded on ``facts`` with each of ``transitions`` an external atom (ASK_TRANSITIONS), and
        their program literals: each solve's assumptions say which hold."""
        control = self._grounded(list(facts) + [clingo.Function(_TRANSITION, s.arguments) for s in transitions],
                                 ASK_TRANSITIONS)
        literal = [control.symbolic_atoms[s].literal for s in transitions]
        for lit in literal:  # an external is false unless assigned, by an assumption of its own: let it free,
            control.assign_external(lit, None)  # so that each solve's assumptions say which hold
        return control, literal

    def __call__(self, model: Sequence[Symbol]) -> list[Symbol] | None:
        own, inputs, links, n = self._reader.split(model)
        if self.fast and self._reader.covers(model):
            shown = self._reader.shown(model)
            return None if shown is None else own + shown
        control = self._grounded(inputs)
        shown: list[list[Symbol]] = []
        result = control.solve(on_model=lambda m: shown.append(m.symbols(shown=True)))
        if not result.satisfiable:
            return None
        return own + list(shown[0])

    def each(self, inputs: Sequence[Symbol], options: Sequence[Sequence[Symbol]] = ((),)) -> list[list[Symbol] | None]:
        """What the levels show of the map made of ``inputs`` (its ``next/3`` and ``dstate/1``) with each
        option's transitions added (``next/3`` atoms, whose dstates are dstates too), or None for an option
        they reject: a map and the ways a new step could extend it (:mod:`.stream`). One grounding: each
        option's transitions are external atoms, assumed true for it and false for the others."""
        if self.fast:
            return [self._reader.shown(list(inputs) + list(option)) for option in options]
        extra = list(dict.fromkeys(s for option in options for s in option))
        control, literal = self._asking(inputs, extra)
        out: list[list[Symbol] | None] = []
        for option in options:
            own = set(option)
            shown: list[list[Symbol]] = []
            control.solve(assumptions=[lit if s in own else -lit for s, lit in zip(extra, literal)],
                          on_model=lambda m: shown.append(m.symbols(shown=True)))
            out.append(shown[0] if shown else None)
        return out

    def reasons(self, model: Sequence[Symbol]) -> list[Symbol]:
        """Of a map the levels reject (the shown symbols of its model), a fewest set of its transitions
        (``next/3``) that they reject alone: no transition of the set can be left out. Where the levels are
        monotone (:attr:`monotone`), every map with these transitions is rejected, so a search may rule
        them out together. Found by QuickXplain (Junker, AAAI 2004) over the map's transitions, each an
        assumption of one small grounding: a few dozen solves (under the stock topological level, a few dozen
        of its Python verdicts: :mod:`.topology`). Empty if the levels accept the map made of
        its transitions alone (as they do any map they reject only for a dstate no transition reaches)."""
        if self.fast:
            transitions, links, n = self._reader.transitions(model)
            return [transitions[i] for i in _fast_reasons(links, n)]
        transitions = [s for s in model if NEXT.matches(s)]
        control, literal = self._asking((), transitions)

        def rejected(chosen: Sequence[int]) -> bool:
            keep = set(chosen)
            return not control.solve(assumptions=[lit if i in keep else -lit
                                                  for i, lit in enumerate(literal)]).satisfiable

        # Every transition assumed: where the levels reject the map, clingo's unsatisfiable core names the
        # assumptions its proof used, a set the levels reject alone (monotone: the transitions left out may
        # as well be false); the fewest are looked for among those, not among all of the map's.
        index = {lit: i for i, lit in enumerate(literal)}
        core: list[int] = []
        if control.solve(assumptions=literal, on_core=core.extend).satisfiable:
            return []
        candidates = sorted({index[lit] for lit in core if lit in index}) or list(range(len(transitions)))
        # (in breadth-first order over the map they draw: see near_first)
        links, n = self._reader.links([transitions[i] for i in candidates])
        candidates = [candidates[k] for k in near_first(links, n, links[0][0])]
        return [transitions[i] for i in _fewest(candidates, rejected)]


def _fast_reasons(links: list[tuple[int, int, int, int]], n: int) -> list[int]:
    """The reasons (indices of ``links``) the stock topological level rejects the map for, read in Python
    (:mod:`.topology`): the links in breadth-first order from where the level finds its first violation, the
    shortest beginning of that order it rejects (a galloping search: the reasons lie around the violation), and
    QuickXplain over that beginning; none where the level accepts the map."""
    found = violation(links, n)
    if found is None:
        return []
    order = near_first(links, n, found[1])

    def rejected(chosen: Sequence[int]) -> bool:
        return violation([links[i] for i in chosen], n) is not None

    # (galloping: the beginnings tried grow from the violation outwards, each check on a few links)
    lo, hi = 1, 1
    while hi < len(order) and not rejected(order[:hi]):
        lo, hi = hi + 1, min(2 * hi, len(order))
    while lo < hi:  # the shortest rejected beginning is order[:hi]
        mid = (lo + hi) // 2
        if rejected(order[:mid]):
            hi = mid
        else:
            lo = mid + 1
    return _fewest(order[:hi], rejected)


def _fewest(candidates: list[int], rejected) -> list[int]:
    """QuickXplain (Junker 2004): a subset of ``candidates`` that ``rejected`` holds of and of no proper
    subset, given that it holds of all of them and that it holds of every superset of a set it holds of."""

    def explain(background: list[int], added: bool, part: list[int]) -> list[int]:
        if added and rejected(background):
            return []
        if len(part) == 1:
            return part
        first, second = part[:len(part) // 2], part[len(part) // 2:]
        need_second = explain(background + first, bool(first), second)
        need_first = explain(background + need_second, bool(need_second), first)
        return need_first + need_second

    return explain([], False, candidates) if candidates else []
