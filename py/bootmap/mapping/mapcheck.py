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
"""

from __future__ import annotations

from typing import Sequence

import clingo
from clingo import Symbol

from .facts import add_facts
from .theory import MAP_INPUTS, Theory

#: What a search without the map's levels shows beside its own atoms: the map the levels judge.
SHOW_MAP = "".join(f"#show {name}/{arity}. " for name, arity in sorted(MAP_INPUTS))

_INPUT_NAMES = frozenset(name for name, _ in MAP_INPUTS)

#: The check shows only what the levels ``#show`` (as beside the other files, which show atoms), not every
#: atom, as a program without any ``#show`` would.
SHOW_ONLY_SHOWN = "#show."


def is_map_input(symbol: Symbol) -> bool:
    """Whether a shown symbol is one of the map's transitions or dstates (shown only for the check)."""
    return any(symbol.match(name, arity) for name, arity in MAP_INPUTS)


class MapCheck:
    """Ask the levels ``levels`` of ``theory`` (each of :attr:`Theory.map_levels`) of one map at a time.

    Calling it with the shown symbols of a model found without those levels (its ``next/3`` and
    ``dstate/1`` among them) gives the model's symbols as the whole theory would show them (the map's
    transitions and dstates left out, the levels' own shown atoms added: places, paths, order and
    sides), or None when the levels reject the map.
    """

    def __init__(self, theory: Theory, levels: Sequence[str]):
        self.files = [str(theory.levels[name]) for name in levels]

    def __call__(self, model: Sequence[Symbol]) -> list[Symbol] | None:
        own, inputs = [], []
        for s in model:  # one call into clingo per symbol: a model lists every time point's dstate
            (inputs if s.name in _INPUT_NAMES and is_map_input(s) else own).append(s)
        control = clingo.Control(["--warn=none"])
        for f in self.files:
            control.load(f)
        control.add("base", [], SHOW_ONLY_SHOWN)
        add_facts(control, inputs)
        control.ground([("base", [])])
        shown: list[list[Symbol]] = []
        result = control.solve(on_model=lambda m: shown.append(m.symbols(shown=True)))
        if not result.satisfiable:
            return None
        return own + list(shown[0])
