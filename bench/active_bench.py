"""Active mapping: actions until the map is unique and true, active against the fixed explorer
and a random walk.

For every hallway world in worlds/*.toml (the worlds explored, not circled: the notched rectangle is a
room the paper's robot circles, where a hallway explorer's travels stop at no place) and every seed, each policy drives the simulated robot:

* ``active`` (``bootmap.agent.active.Active``): explores and rehearses until its own map is unique and
  complete, and stops;
* ``explore`` (``bootmap.sim.policies.Explore``): the fixed systematic explorer, wandering on at random
  once everything is explored (so it can go on to ``--max-steps``);
* ``random`` (``bootmap.sim.policies.RandomWalk``): a seeded random walk.

Every run is scored the same way: its images are labelled with views in order (``OnlineViews``, as the
active robot labels them), and the map of every prefix (``Mapper.stream``, actions read in quarter turns) is
compared with the world's truth. The figure is the number of actions after which the map is first
unique, proved minimal, with the true numbers of dstates, places and paths, and every time point on its
true dstate (up to renaming); "-" when that never happens within ``--max-steps`` dstates.

    .venv/bin/python bench/active_bench.py --seeds 0-4 --figure docs/active.png
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from targets import Targets  # noqa: E402

from bootmap import arguments  # noqa: E402
from bootmap.errors import SolveTimeout  # noqa: E402
from bootmap.mapping.api import Mapper  # noqa: E402
from bootmap.metrics import dstate_accuracy  # noqa: E402
from bootmap.sim import Explore, RandomWalk, Simulation, SimulationError  # noqa: E402
from bootmap.agent.active import QUANTUM_DEG, Active  # noqa: E402
from bootmap.sim.world import load_world, worlds_dir  # noqa: E402
from bootmap.tableau import Step, Tableau  # noqa: E402
from bootmap.views import OnlineViews  # noqa: E402

POLICIES = ("active", "explore", "random")


def make(policy: str, world, max_steps: int):
    if policy == "active":
        return Active(max_steps=max_steps, max_range=world.laser.range_max)
    if policy == "explore":
        return Explore(wander=True)
    return RandomWalk()


def actions_until_true(tableau: Tableau, world) -> int | None:
    """Actions after which the map of the experience is first unique and true (None: never)."""
    views = OnlineViews(max_range=world.laser.range_max).labels([s.image for s in tableau.steps])
    labelled = Tableau(tuple(Step(v, s.action) for v, s in zip(views, tableau.steps)))
    truth = [s.truth for s in tableau.steps]
    want = (world.truth_dstates, len(world.places), len(world.paths))
    mapper = Mapper(quantum_deg=QUANTUM_DEG, how="fewest")
    stream = mapper.stream()
    for n in range(2, len(labelled) + 1):
        if len(set(truth[:n])) < world.truth_dstates:
            continue  # not every true dstate seen yet: the map cannot be true (and need not be found)
        try:
            m = mapper.map(labelled.prefix(n), stream=stream)
        except SolveTimeout:
            continue  # no map proved minimal for this prefix: not (yet) the true one
        if m.unique and m.minimal and (m.n_dstates, m.n_places, m.n_paths) == want \
                and dstate_accuracy(truth[:n], m.dstate_of) == 1.0:
            return n - 1
    return None


def measure(world, policy: str, seed: int, max_steps: int) -> dict:
    started = time.perf_counter()
    pol = make(policy, world, max_steps)
    stuck = None
    try:
        result = Simulation(world).reset(seed).run(pol, n_steps=max_steps)
    except SimulationError as e:  # the turn law can spin at a crossing: score the experience up to there
        if e.run is None:
            return {"world": world.name, "policy": policy, "seed": seed, "error": str(e)}
        result, stuck = e.run, str(e)
    row = {"world": world.name, "policy": policy, "seed": seed, "steps": len(result.tableau),
           "until_true": actions_until_true(result.tableau, world), "stuck": stuck}
    if policy == "active":
        m = pol.map_
        row.update(stopped_after=len(result.tableau) - 1, complete=pol.complete_, rehearsals=pol.rehearsals_,
                   turnarounds=pol.turnarounds_, final=(m.n_dstates, m.n_places, m.n_paths), unique=m.unique)
    row["seconds"] = round(time.perf_counter() - started, 1)
    return row


def _mean(xs):
    xs = [x for x in xs if x is not None]
    return statistics.mean(xs) if xs else None


def table(rows: list[dict], worlds: list, seeds: list[int]) -> str:
    lines = ["| world | truth (dstates / places / paths) | active: actions until true | active: stopped after "
             "(final map) | explore: actions until true | random walk: actions until true | random / active |",
             "|---|---|---|---|---|---|---|"]
    for w in worlds:
        by = {p: [r for r in rows if r["world"] == w.name and r["policy"] == p] for p in POLICIES}
        cell = {p: _cell([r.get("until_true") for r in by[p]], len(seeds)) for p in POLICIES}
        stop = _cell([r.get("stopped_after") for r in by["active"]], len(seeds))
        finals = sorted({"/".join(map(str, r["final"])) for r in by["active"] if "final" in r})
        ratio = _ratio(by)
        lines.append(f"| {w.name} | {w.truth_dstates} / {len(w.places)} / {len(w.paths)} | {cell['active']} | "
                     f"{stop} ({', '.join(finals)}) | {cell['explore']} | {cell['random']} | "
                     f"{'-' if ratio is None else f'{ratio:.1f}x'} |")
    return "\n".join(lines)


def _cell(values: list, n: int) -> str:
    got = [v for v in values if v is not None]
    if not got:
        return f"- (0 of {n})"
    return f"{statistics.mean(got):.1f} [{min(got)}-{max(got)}] ({len(got)} of {n})"


def _ratio(by: dict) -> float | None:
    """Random walk's mean actions until true over active's; a random walk that never got there within
    the cap counts as the cap (so the ratio is a lower bound)."""
    active = _mean([r.get("until_true") for r in by["active"]])
    rand = [r.get("until_true") if r.get("until_true") is not None else r.get("steps", 0) - 1 for r in by["random"]]
    if active is None or not rand:
        return None
    return statistics.mean(rand) / active


def figure(rows: list[dict], worlds: list, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    width = 0.26
    colours = {"active": "tab:green", "explore": "tab:blue", "random": "tab:grey"}
    for j, p in enumerate(POLICIES):
        ax.bar(0, 0, 0, color=colours[p], label=p, alpha=0.8)  # in the legend even where no bar is drawn
        for i, w in enumerate(worlds):
            vals = [r.get("until_true") for r in rows if r["world"] == w.name and r["policy"] == p]
            got = [v for v in vals if v is not None]
            x = i + (j - 1) * width
            if got:
                ax.bar(x, statistics.mean(got), width, color=colours[p], alpha=0.8)
                ax.scatter([x] * len(got), got, s=10, color="black", zorder=3)
            missed = len(vals) - len(got)
            if missed:
                ax.text(x, 2, f"{missed}x\nnever", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(range(len(worlds)), [w.name for w in worlds])
    ax.set_ylabel("actions until the map is unique and true")
    ax.set_title("Active mapping against the fixed explorer and a random walk (dots: seeds)")
    ax.legend()
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=arguments.seeds, default=[0, 1, 2, 3, 4], metavar="S1,S2,... or A-B")
    ap.add_argument("--worlds", nargs="*", help="world names (default: every hallway world in worlds/)")
    ap.add_argument("--max-steps", type=arguments.count("max-steps", 2), default=400,
                    help="dstates per run at most (default 400)")
    ap.add_argument("--figure", metavar="FILE.png", help="write the figure here")
    args = ap.parse_args(argv)
    names = args.worlds or sorted(p.stem for p in worlds_dir().glob("*.toml"))
    worlds = [w for w in map(load_world, names) if args.worlds or w.policy == "explore"]
    rows = []
    for w in worlds:
        for seed in args.seeds:
            for p in POLICIES:
                row = measure(w, p, seed, args.max_steps)
                rows.append(row)
                print(row, flush=True)
    print()
    print(table(rows, worlds, args.seeds))
    if args.figure:
        figure(rows, worlds, args.figure)
        print(f"\nwrote {args.figure}")
    targets = Targets()
    for w in worlds:
        by = {p: [r for r in rows if r["world"] == w.name and r["policy"] == p] for p in POLICIES}
        true = sum(r.get("until_true") is not None for r in by["active"])
        targets.check(f"{w.name}: active runs whose map becomes unique and true", true, "==", len(args.seeds),
                      fmt="{}", bound_text=f"{len(args.seeds)} (every seed)")
        targets.check(f"{w.name}: random walk / active, actions until true", _ratio(by), ">=", 2, fmt="{:.1f}x",
                      bound_text="2x")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
