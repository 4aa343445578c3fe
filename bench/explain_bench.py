"""How long an explanation takes: pairs of time points of the paper's 401-step tableau.

For each pair and each set of levels: the verdict, the evidence size, the axioms the proof needs and
the wall time of the whole explanation (resolving the map, finding and minimising the evidence, the
proof). Target: under 1 s per pair (median of --repeat runs), printed beside the slowest pair; the exit
status is 1 if it is missed.

Run: .venv/bin/python bench/explain_bench.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

from bootmap.examples import notched_rectangle
from bootmap.mapping.explain import Explainer
from targets import Targets

PAIRS = [("S0", "S4"), ("t0", "t8"), ("S1", "S5"), ("t0", "t1"), ("t100", "t396")]
LEVELS = {"all levels": None, "causal+topological": ["causal", "topological"]}
MAX_S = 1.0  # one whole explanation


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    tableau = notched_rectangle(50)
    print(f"paper tableau: {len(tableau)} steps; median of {args.repeat} runs\n")
    print(f"{'levels':20s} {'pair':12s} {'verdict':10s} {'evidence':>8s} {'axioms':28s} {'time':>8s}")
    worst = 0.0
    for label, levels in LEVELS.items():
        explainer = Explainer(levels=levels)
        for a, b in PAIRS:
            times = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                e = explainer.explain(tableau, a, b)
                times.append(time.perf_counter() - t0)
            median = statistics.median(times)
            worst = max(worst, median)
            axioms = ",".join(r.name for r in e.axioms) or "-"
            print(f"{label:20s} {a + '/' + b:12s} {e.verdict:10s} {len(e.evidence):8d} {axioms:28s} {median:7.3f}s")
    print()
    targets = Targets()
    targets.check("slowest pair", worst, "<", MAX_S, fmt="{:.3f}", unit=" s")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
