"""The map: the tableau resolved into dstates, places and paths by the axioms in ``asp/``, and why.

This package is the boundary between Python and the answer set programs. Everything outside it maps
through :class:`~.api.Mapper` (``bootmap.mapping.Mapper``), which chooses the search once. Reading order:

* :mod:`.api` - the one door: a map, an explanation, a stream, a rehearsal;
* :mod:`.vocabulary` - every predicate that crosses the boundary, with how it reads to a person;
* :mod:`.theory` - the .lp files of the axiom directory, grouped into levels, with their named rules;
* :mod:`.motion` - the robot's action types, learned from the angles it measured;
* :mod:`.facts` - a tableau as clingo facts (symbols, never program text);
* :mod:`.grounding` - one clingo control: ground, solve by a deadline, read the prepass;
* :mod:`.resolver` - the search for the minimal maps (which groundings to make);
* :mod:`.cogmap` - the map named as the paper names it (S0, P0, Pa0);
* :mod:`.diagnosis` - which level fails when no map satisfies the axioms;
* :mod:`.trace`, :mod:`.proof`, :mod:`.explain` - why two time points are different dstates, or the same.
"""

from importlib import import_module

# Imported on first use (PEP 562): the vocabulary's constants should not cost every command clingo's and
# the whole package's import.
_HOMES = {"Mapper": "api", "CognitiveMap": "cogmap", "SolveStats": "cogmap", "Explainer": "explain", "Explanation": "explain",
          "Deadline": "grounding", "Resolver": "resolver", "Theory": "theory", "load_theory": "theory"}

__all__ = sorted(_HOMES)


def __getattr__(name: str):
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f".{_HOMES[name]}", __name__), name)
