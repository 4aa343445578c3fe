"""Is the map's confidence calibrated? A dstate every minimal map agrees on should be a true dstate.

Random grid worlds (tests/support/gridworld, seeds not used elsewhere) are explored for a few steps, too
few to tell every dstate apart, so the experience leaves several minimal maps. For every dstate of a map
the minimal maps found all agree on (``settled``), the check is whether its time points are exactly the
visits of one true dstate; the same is reported for the dstates they disagree on, and over maps whose
enumeration was capped apart. Exits 1 when settled dstates are true less than 99% of the time.

    PYTHONPATH=py:bench .venv/bin/python bench/confidence_bench.py --cases 1500 --first-seed 20000
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
from tqdm import tqdm

from bootmap.mapping.resolver import Resolver

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds
from support.gridworld import random_world, walk  # noqa: E402

TARGET = 0.99


def true_groups(truth: list[str]) -> set[frozenset[int]]:
    groups: dict[str, set[int]] = defaultdict(set)
    for t, x in enumerate(truth):
        groups[x].add(t)
    return {frozenset(g) for g in groups.values()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=300)
    ap.add_argument("--first-seed", type=int, default=9000)
    ap.add_argument("--levels", help="levels to map with, e.g. causal,topological (default: every level)")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    resolver = Resolver(levels=args.levels.split(",") if args.levels else None, time_limit=30, misreads=False)
    counts = {k: [0, 0] for k in ("settled", "unsettled", "settled, capped")}  # [true, all]
    ambiguous = capped = 0
    settled_share = []
    for seed in tqdm(range(args.first_seed, args.first_seed + args.cases), desc="walks", unit="walk",
                     disable=args.no_progress):
        rng = np.random.default_rng(seed)
        world = random_world(rng, int(rng.integers(3, 5)), int(rng.integers(3, 5)),
                             extra_edges=int(rng.integers(0, 4)), landmarks=0.2)
        tableau = walk(world, int(rng.integers(8, 30)), rng, policy="explore")
        cmap = resolver.resolve(tableau)
        c = cmap.confidence
        if c.maps < 2 and not c.capped:
            continue
        ambiguous += 1
        capped += c.capped
        settled_share.append(c.settled)
        truth = true_groups([s.truth for s in tableau.steps])
        mine: dict[str, set[int]] = defaultdict(set)
        for t, d in enumerate(cmap.dstate_of):
            mine[d].add(t)
        for d, ts in mine.items():
            kind = ("settled, capped" if c.capped else "settled") if d not in c.unsettled else "unsettled"
            counts[kind][0] += frozenset(ts) in truth
            counts[kind][1] += 1
    print(f"{args.cases} walks ({', '.join(resolver.theory.levels)}); {ambiguous} with several minimal maps ({capped} capped); "
          f"time points settled per map: median {100 * float(np.median(settled_share or [0])):.0f}%")
    for kind, (true, total) in counts.items():
        share = true / total if total else float("nan")
        print(f"  {kind:16} dstates: {total:5}; a true dstate exactly: {true:5} ({100 * share:.1f}%)")
    true, total = counts["settled"]
    ok = total > 0 and true / total >= TARGET
    print(f"settled dstates true: {100 * true / max(1, total):.1f}% (target >= {100 * TARGET:.0f}%): "
          f"{'met' if ok else 'MISSED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
