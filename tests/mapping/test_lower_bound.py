"""The dstates the resolver proves necessary agree with brute force over every partition of tiny tableaux.

The brute force is independent of clingo: it tries every partition of the time points into dstates (within
views, which one dstate never mixes) and checks each with the Python re-statement of the axioms
(:func:`support.check.check_map`). The fewest dstates any valid partition has is what a proof of
a lower bound may claim and no more; the valid partitions with that many are the minimal maps.
"""

from __future__ import annotations

import itertools
from collections import defaultdict

import pytest

from bootmap.errors import SolveTimeout
from bootmap.mapping import Resolver
from support.check import check_map

from test_axiom_rules import grid_walk

CT = ("causal", "topological")


def set_partitions(items: list[int]):
    """Every partition of ``items`` as a block index per item (restricted growth strings)."""
    def grow(i: int, labels: list[int], blocks: int):
        if i == len(items):
            yield list(labels)
            return
        for b in range(blocks + 1):
            labels.append(b)
            yield from grow(i + 1, labels, max(blocks, b + 1))
            labels.pop()
    yield from grow(0, [], 0)


def brute_force_minimal_maps(tableau, levels) -> tuple[int, int]:
    """(fewest dstates of any partition the axioms accept, how many partitions have that few)."""
    by_view = defaultdict(list)
    for t, v in enumerate(tableau.views):
        by_view[v].append(t)
    classes = list(by_view.values())
    best, count = None, 0
    for choice in itertools.product(*(list(set_partitions(c)) for c in classes)):
        dstate_of = [None] * len(tableau)
        for k, (members, labels) in enumerate(zip(classes, choice)):
            for t, b in zip(members, labels):
                dstate_of[t] = f"{k}.{b}"
        n = len(set(dstate_of))
        if best is not None and n > best:
            continue
        if check_map(tableau, dstate_of, levels):
            continue
        if best is None or n < best:
            best, count = n, 1
        else:
            count += 1
    return best, count


# Walks whose classes' lower bound (what the views seen later tell apart) falls short of the truth: the
# resolver refutes bounds below the minimum (their tries say "at most N dstates: unsat"); above the lower
# bound its searches optimise, so the last two bounds may be answered by one search of the higher.
@pytest.mark.parametrize("seed", [42, 51])
def test_the_proved_lower_bound_is_the_brute_force_minimum_where_bounds_are_refuted(seed):
    tableau = grid_walk(seed)
    fewest, n_minimal = brute_force_minimal_maps(tableau, CT)
    m = Resolver(levels=CT, time_limit=60).resolve(tableau)
    refuted = [int(b.dstates.split()[2]) for b in m.stats.bounds
               if b.dstates.startswith("at most") and b.result == "unsat"]
    assert refuted and max(refuted) in (fewest - 2, fewest - 1)  # the case this test is about
    assert m.n_dstates == fewest and m.n_models == n_minimal and m.minimal
    assert m.stats.lower_bound == fewest  # refuted below, or the optimum of the search above: proved


def test_a_time_out_reports_what_its_stage_proved_and_no_more_than_brute_force_needs():
    tableau = grid_walk(51)
    fewest, _ = brute_force_minimal_maps(tableau, CT)
    with pytest.raises(SolveTimeout) as e:
        Resolver(levels=CT, time_limit=0.0).resolve(tableau)
    # Out of time in the first try (one dstate per view), the views, which no dstate mixes, are proved; once
    # it failed, one dstate more. Where the clock stops depends on the machine; what that proves does not.
    views = len(set(tableau.views))
    assert (e.value.stage, e.value.lower_bound) in {("one dstate per class", views), ("the lower bounds", views + 1)}
    assert e.value.lower_bound < fewest


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_the_prepass_reads_exactly_the_features_that_tell_a_class_apart(seed):
    """core/prepass.lp's telling/3 is every feature only some time points show whose class shows it with
    two values or more (computed here from all feature/3 atoms), and only the prepass grounds it."""
    import numpy as np

    from bootmap.mapping.facts import read_actions, tableau_facts
    from bootmap.mapping.grounding import Grounding, prepass
    from bootmap.mapping.vocabulary import CLASS_KEY, FEATURE, SHOWN_BY_ALL, TELLING
    from support.gridworld import random_world, walk

    rng = np.random.default_rng(seed)
    tableau = walk(random_world(rng, 4, 3, extra_edges=2, landmarks=0.3), 120, rng, policy="explore")
    resolver = Resolver()
    facts = tableau_facts(tableau, angles=read_actions(tableau)[0])
    grounded = prepass(resolver.theory, facts, resolver.future_depth)
    grouping = {f for (f,) in SHOWN_BY_ALL.facts_in(grounded.control)}
    key_of = {t.number: k for t, k in CLASS_KEY.facts_in(grounded.control)}
    values = defaultdict(set)
    partial = [(t.number, f, x) for t, f, x in FEATURE.facts_in(grounded.control) if f not in grouping]
    for t, f, x in partial:
        values[key_of[t], f].add(x)
    expected = {(t, f, x) for t, f, x in partial if len(values[key_of[t], f]) > 1}
    telling = {(t.number, f, x) for t, f, x in TELLING.facts_in(grounded.control)}
    assert telling == expected and 0 < len(telling) < len(partial)
    plain = Grounding(resolver.theory, facts, resolver.future_depth).ground()
    assert not list(TELLING.facts_in(plain.control))


def test_an_axiom_directory_copied_without_the_prepass_part_proves_the_same_bounds(tmp_path):
    """A user's copy of asp/ made before core/prepass.lp existed: the lower bounds are read from every
    feature instead of the telling ones, and come out the same."""
    import shutil

    import numpy as np

    from bootmap.mapping.facts import read_actions, tableau_facts
    from bootmap.mapping.grounding import prepass
    from bootmap.mapping.theory import default_axioms_dir
    from support.gridworld import random_world, walk

    old = tmp_path / "asp"
    shutil.copytree(default_axioms_dir(), old)
    (old / "core" / "prepass.lp").unlink()
    rng = np.random.default_rng(2)
    tableau = walk(random_world(rng, 4, 4, extra_edges=2, landmarks=0.0), 200, rng, policy="explore")
    facts = tableau_facts(tableau, angles=read_actions(tableau)[0])
    bounds = []
    for resolver in (Resolver(), Resolver(axioms=old)):
        grounded = prepass(resolver.theory, facts, resolver.future_depth)
        classes = grounded.classes(range(len(tableau)))
        bounds.append(grounded.lower_bounds(classes))
    assert bounds[0] == bounds[1] and sum(bounds[0]) > len(bounds[0])  # the bounds say more than one a class


def test_a_bound_the_caller_proved_skips_the_tries_below_it_and_keeps_the_map():
    # A 98-step exploration whose classes bound it at 49 dstates, where the minimal maps have 51: told
    # 51 (a stream knows it from the map before the last step), the search starts there.
    import numpy as np
    from support.gridworld import random_world, walk

    rng = np.random.default_rng(3)
    tableau = walk(random_world(rng, 6, 5, extra_edges=4, landmarks=0.4), 98, rng, policy="explore")
    resolver = Resolver(time_limit=60)
    alone = resolver.resolve(tableau)
    told = resolver.resolve(tableau, at_least=alone.n_dstates)
    refuted = [t.dstates for t in alone.stats.bounds if t.result == "unsat" and t.dstates.startswith("at most")]
    assert refuted, "the classes' bound falls short here: the case needs it"
    # the answer at once (a try without the topological level that settled nothing is made again with
    # it): with fewer classes than the dstates the caller proved, one dstate per class is not tried
    assert told.stats.classes < alone.n_dstates
    assert [t.result for t in told.stats.bounds if t.result != "unsettled"] == ["sat"]
    assert [t.dstates for t in alone.stats.bounds][0] == "one dstate per class"
    a, b = alone.to_dict(), told.to_dict()
    a.pop("stats"), b.pop("stats")
    assert a == b and told.minimal and told.stats.lower_bound == alone.n_dstates
