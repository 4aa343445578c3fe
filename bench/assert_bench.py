"""A person's assertions: how long until an assertion is answered (the map that honours it, or the clash).

The map before the assertion is known (the service keeps it; the command line made it): what is timed is
``Mapper.honour`` with it given, i.e. the map re-solved with the assertion and what changed, or the clash
with its proof. On the paper's tableau (401 steps) and on a 2,000-step exploration of a random grid world
(the stream bench's), each case the median of ``--repeats`` runs. Exits 1 when a target is missed.

    PYTHONPATH=py:bench .venv/bin/python bench/assert_bench.py
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from bootmap import examples
from bootmap.mapping.api import Mapper
from bootmap.mapping.assertions import parse_assertions

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds
from support.gridworld import random_world, walk  # noqa: E402

#: seconds: on the paper's tableau, on a 2,000-step tableau
TARGETS = {"paper": 0.1, "long": 1.0}


def cases(tableau, before) -> list[tuple[str, list[dict]]]:
    """A split (apart of two visits of one dstate), a join the experience leaves possible or refutes
    (same of two time points with one view, at different dstates), and a clash of two assertions."""
    dstate_of, views = before.dstate_of, tableau.views
    n = len(tableau)
    apart = next((a, b) for a in range(n // 2, n) for b in range(a + 1, n) if dstate_of[a] == dstate_of[b])
    same = next((a, b) for a in range(n // 2, n) for b in range(a + 1, n)
                if views[a] == views[b] and dstate_of[a] != dstate_of[b])
    first = next((a, b) for a in range(n - 1) for b in range(a + 1, n - 1)
                 if dstate_of[a] == dstate_of[b] and dstate_of[a + 1] == dstate_of[b + 1]
                 and tableau.steps[a].action == tableau.steps[b].action)
    return [(f"apart(t{apart[0]}, t{apart[1]})", [{"apart": list(apart)}]),
            (f"same(t{same[0]}, t{same[1]})", [{"same": list(same)}]),
            (f"same(t{first[0]}, t{first[1]}) with apart(t{first[0] + 1}, t{first[1] + 1})",
             [{"same": list(first)}, {"apart": [first[0] + 1, first[1] + 1]}])]


def timed(mapper: Mapper, tableau, before, entries, repeats: int) -> tuple[float, str]:
    said = parse_assertions(entries, len(tableau))
    seconds, answer = [], ""
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = mapper.honour(tableau, said, before=before)
        seconds.append(time.perf_counter() - t0)
        answer = (f"clash of {len(result.conflict.assertions)}" if result.conflict else
                  f"{result.after.n_dstates} dstates ({result.before.n_dstates} before)")
    return statistics.median(seconds), answer


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--steps", type=int, default=2000)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(3)
    world = random_world(rng, 6, 5, extra_edges=4, landmarks=0.4)
    tableaux = {"paper": examples.notched_rectangle(circuits=50),
                "long": walk(world, args.steps, rng, policy="explore")}
    missed = []
    print(f"{'tableau':8} {'steps':>6} {'assertion':52} {'answer':28} {'median s':>9}  target")
    for name, tableau in tableaux.items():
        mapper = Mapper(time_limit=120)
        t0 = time.perf_counter()
        before = mapper.map(tableau)
        print(f"{name:8} {len(tableau):6} {'(the map without assertions)':52} {f'{before.n_dstates} dstates':28} "
              f"{time.perf_counter() - t0:9.3f}")
        for label, entries in cases(tableau, before):
            s, answer = timed(mapper, tableau, before, entries, args.repeats)
            ok = s < TARGETS[name]
            missed += [] if ok else [f"{name} {label}"]
            print(f"{name:8} {len(tableau):6} {label:52} {answer:28} {s:9.3f}  < {TARGETS[name]:g} s "
                  f"{'ok' if ok else 'MISSED'}")
    print("every target met" if not missed else f"missed: {'; '.join(missed)}")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
