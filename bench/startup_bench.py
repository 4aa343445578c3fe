"""How fast the command starts: `bootmap --help`, and `bootmap map` on the paper's 401-step tableau, end
to end (a new process each time, imports included), the median of several runs.

Targets: --help under 0.2 s; map under 0.5 s.

Run: .venv/bin/python bench/startup_bench.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

from targets import Targets

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "tests" / "data" / "paper_notched_rectangle.json"


def seconds(args: list[str], repeat: int) -> float:
    """Median wall-clock seconds of ``bootmap ARGS`` in a new process."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "bootmap.cli", *args], check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=7, help="runs of each command; the median is reported")
    args = p.parse_args(argv)
    help_s = seconds(["--help"], args.repeat)
    map_s = seconds(["map", str(PAPER)], args.repeat)
    print(f"bootmap --help: {help_s:.3f} s; bootmap map (the paper's 401 steps): {map_s:.3f} s "
          f"(medians of {args.repeat})")
    targets = Targets()
    targets.check("bootmap --help", help_s, "<", 0.2, fmt="{:.3f}", unit=" s")
    targets.check("bootmap map, the paper's tableau, end to end", map_s, "<", 0.5, fmt="{:.3f}", unit=" s")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
