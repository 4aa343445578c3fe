"""The map: the tableau resolved into dstates, places and paths by the axioms in ``asp/``, and why.

This package is the boundary between Python and the answer set programs. Reading order:

* :mod:`.vocabulary` - every predicate that crosses the boundary, with how it reads to a person;
* :mod:`.theory` - the .lp files of the axiom directory, grouped into levels, with their named rules;
* :mod:`.facts` - a tableau as clingo facts (symbols, never program text);
* :mod:`.grounding` - one clingo control: ground, solve by a deadline, read the prepass;
* :mod:`.resolver` - the search for the minimal maps (which groundings to make);
* :mod:`.cogmap` - the map named as the paper names it (S0, P0, Pa0);
* :mod:`.diagnosis` - which level fails when no map satisfies the axioms;
* :mod:`.trace`, :mod:`.proof`, :mod:`.explain` - why two time points are different dstates, or the same.
"""

from .cogmap import CognitiveMap, SolveStats
from .explain import Explainer, Explanation
from .grounding import Deadline
from .resolver import Resolver
from .theory import Theory, load_theory

__all__ = ["CognitiveMap", "Deadline", "Explainer", "Explanation", "Resolver", "SolveStats", "Theory", "load_theory"]
