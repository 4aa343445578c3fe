"""A manual loop closure: where drifting odometry withholds true joins, does asserting one recover the map?

Random grid worlds (tests/support/gridworld, 8 m cells, seeds not used elsewhere) are explored; each step
carries odometry that drifts (its heading wanders by ``--drift-deg`` per travel, so far revisits are
dead-reckoned metres from where the robot was), and loop closing maps it: only visits odometry puts near
each other (or that retrace the same actions) are proposed as one dstate. Where the map keeps one true
dstate in two and joins nothing wrongly (one true join withheld), that join is asserted (``same``) and the
map made again: is it now the true map? Every walk is counted: exact already, a wrong join already made
(no ``same`` undoes that), one join withheld (recovered or not), more withheld (the earliest asserted:
does the map get closer?). Exits 1 when fewer than 90% of at least 30 one-join cases are recovered.

    PYTHONPATH=py:bench .venv/bin/python bench/assert_recovery_bench.py --cases 30
"""

from __future__ import annotations

import argparse
import math
import sys
from collections import Counter
from pathlib import Path

import numpy as np
from tqdm import tqdm

from bootmap.mapping.api import Mapper
from bootmap.mapping.assertions import parse_assertions
from bootmap.tableau import Tableau

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds
from support.gridworld import random_world, walk  # noqa: E402

TARGET = 0.9


def drifting(tableau: Tableau, rng: np.random.Generator, drift_deg: float) -> Tableau:
    """The tableau with odometry at every step: the true motion, its heading wandering ``drift_deg`` (sd)
    at each travel, integrated from the first pose."""
    doc = tableau.to_dict()
    x, y, h = doc["steps"][0]["pose"]
    error = 0.0
    for t, step in enumerate(doc["steps"]):
        step["odometry"] = [x, y, h + error]
        if t + 1 < len(doc["steps"]):
            nxt = doc["steps"][t + 1]["pose"]
            if step["action"]["type"] == "travel":
                error += math.radians(rng.normal(0.0, drift_deg))
            dist = math.hypot(nxt[0] - step["pose"][0], nxt[1] - step["pose"][1])
            along = math.atan2(nxt[1] - step["pose"][1], nxt[0] - step["pose"][0]) if dist else 0.0
            x += dist * math.cos(along + error)
            y += dist * math.sin(along + error)
            h = nxt[2]
    return Tableau.from_dict(doc)


def partition(labels) -> frozenset:
    groups: dict = {}
    for t, x in enumerate(labels):
        groups.setdefault(x, set()).add(t)
    return frozenset(frozenset(g) for g in groups.values())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=30, help="maps with one true join withheld, to collect")
    ap.add_argument("--first-seed", type=int, default=31000)
    ap.add_argument("--drift-deg", type=float, default=6.0)
    ap.add_argument("--max-walks", type=int, default=2000)
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    mapper = Mapper(how="loops", time_limit=60)
    outcome: Counter = Counter()
    bar = tqdm(total=args.cases, desc="one join withheld", unit="case", disable=args.no_progress)
    walks = 0
    for seed in range(args.first_seed, args.first_seed + args.max_walks):
        if outcome["one: recovered"] + outcome["one: not recovered"] >= args.cases:
            break
        walks += 1
        rng = np.random.default_rng(seed)
        world = random_world(rng, int(rng.integers(3, 5)), int(rng.integers(3, 5)),
                             extra_edges=int(rng.integers(1, 4)), landmarks=0.6, cell_m=8.0)
        tableau = drifting(walk(world, int(rng.integers(25, 45)), rng, policy="explore"), rng, args.drift_deg)
        truth = [s.truth for s in tableau.steps]
        before = mapper.map(tableau)
        mine, true = partition(before.dstate_of), partition(truth)
        if mine == true:
            outcome["exact already"] += 1
            continue
        if any(not any(g <= tg for tg in true) for g in mine):
            outcome["a wrong join made"] += 1
            continue
        n = len(truth)
        a, b = next((a, b) for b in range(n) for a in range(b) if truth[a] == truth[b]
                    and before.dstate_of[a] != before.dstate_of[b])
        result = mapper.honour(tableau, parse_assertions([{"same": [a, b]}], n), before=before)
        extra = len(mine) - len(true)
        kind = "one" if extra == 1 else "more"
        if result.conflict is not None:
            outcome[f"{kind}: refused"] += 1
            continue
        after = partition(result.after.dstate_of)
        if kind == "one":
            outcome["one: recovered" if after == true else "one: not recovered"] += 1
            bar.update(1)
        else:
            off = len(after) - len(true)
            outcome["more: recovered" if after == true else "more: closer" if off < extra else
                    "more: as far" if off == extra else "more: farther"] += 1
    bar.close()
    print(f"{walks} grid-world explorations (seeds {args.first_seed}-{args.first_seed + walks - 1}, 8 m cells), "
          f"odometry heading drift {args.drift_deg:g} deg (sd) per travel, mapped by loop closing:")
    print(f"  exact already: {outcome['exact already']}; a wrong join made (no same undoes it): "
          f"{outcome['a wrong join made']}")
    print(f"  one true join withheld: asserting it recovers the true map {outcome['one: recovered']}, not "
          f"{outcome['one: not recovered']}, refused {outcome['one: refused']}")
    print(f"  more withheld, the earliest asserted: recovered {outcome['more: recovered']}, closer "
          f"{outcome['more: closer']}, as far {outcome['more: as far']}, farther {outcome['more: farther']}, "
          f"refused {outcome['more: refused']}")
    fixable = outcome["one: recovered"] + outcome["one: not recovered"] + outcome["one: refused"]
    share = outcome["one: recovered"] / fixable if fixable else 0.0
    ok = share >= TARGET and fixable >= 30
    print(f"one withheld join asserted recovers the true map in {outcome['one: recovered']} of {fixable} cases "
          f"({100 * share:.0f}%; target >= {100 * TARGET:.0f}% over >= 30): {'met' if ok else 'MISSED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
