"""Tools that serve bootmap's tests and benchmarks, not the pipeline.

:mod:`support.check` re-checks every axiom of ``asp/`` independently, in plain Python without
clingo: a test oracle for the resolver. :mod:`support.gridworld` builds random grid worlds and
walks through them, tableaux whose true map is known and satisfies every axiom. Nothing in the pipeline
(simulation, views, resolver, recognition, service) imports this package.
"""
