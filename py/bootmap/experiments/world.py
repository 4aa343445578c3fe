"""The paper's whole experiment: simulate -> views -> map -> recognise, with a report.

1. The robot explores a world (``bootmap.sim``): images at dstates, actions, truth.
2. Images are clustered into views, k chosen by the internal measure M (``bootmap.views``); U(V|S)
   against the truth says whether the views removed image variability.
3. The view/action tableau is resolved into dstates, places and paths (``bootmap.mapping.resolver``) and scored
   against the truth up to renaming.
4. Every image, labelled by its resolved dstate, trains a recogniser (``bootmap.recognise``): the online
   curve and 10-fold cross-validated learning curves.

``run_experiment`` returns the results as a dict and, given ``out_dir``, writes ``results.json``,
``report.md`` and figures there. The results include :func:`checks`, what the paper's experiment must
show, each True or False; the report says which hold, and names the true dstates a map merged or split
rather than claim success. ``run_seeds`` repeats it over seeds with the paper's figures alongside.
"""

from __future__ import annotations

import json
import time
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..arguments import DEFAULT_LEARNER
from ..errors import BadInput, BootmapError, SolveTimeout
from ..mapping.resolver import Resolver
from ..metrics import dstate_accuracy
from ..recognise import (TooFewImages, default_learners, fitting_sizes, learning_curve_cv, online_curve,
                         online_hits)
from ..sim import simulate
from ..agent import POLICIES, make_policy
from ..sim.world import World, load_world
from ..views import ViewClusterer, view_labels, view_table
from .runs import RunStore

CURVE_SIZES = (10, 20, 30, 40, 50, 60, 70, 80, 90)
#: ... and of the learner drawn beside nearest neighbour: fewer, as its fits (a choice between two learners by
#: inner folds, each aligning every image) cost a hundred times nearest neighbour's.
LEARNER_CURVE_SIZES = (10, 30, 60, 90)
PAPER_CIRCUITS = 50  # the paper's notched-rectangle run: 50 circuits, 400 images
PAPER_EXPLORE_STEPS = 100  # the paper's Taylor Hall run: 100 images
NN_TARGET = 0.85  # nearest neighbour after 90 images: the paper reports about 90% and 88%


class Laps:
    """Seconds each stage of an experiment took: ``lap("views_s")`` records the time since the last lap
    (or since the timer was made) under that name in ``timings``."""

    def __init__(self):
        self.timings: dict[str, float] = {}
        self._clock = time.perf_counter()

    def __call__(self, name: str) -> None:
        now = time.perf_counter()
        self.timings[name] = round(now - self._clock, 3)
        self._clock = now


def run_experiment(world: str | World, circuits: int | None = None, steps: int | None = None, seed: int = 0,
                   out_dir: str | Path | None = None, k_max: int = 12, progress: bool = False,
                   time_limit: float = 60.0, levels: list[str] | None = None,
                   quantum_deg: float | None = None, clusterer: str = "kmeans", learner: str = DEFAULT_LEARNER,
                   blas_threads: int | None = 1, policy: str | None = None,
                   runs: RunStore | None = None) -> dict:
    """Run the experiment on one world; see the module docstring.

    The run length defaults to the paper's: 50 circuits of a room (``circuits`` policy), 100 dstates of
    an explored hallway (``explore`` policy). ``policy`` overrides the world's (``active`` explores until
    its own map is unique and complete, ``steps`` capping it; ``random`` walks). ``levels`` restricts the map's axioms (default: all);
    ``quantum_deg`` rounds the actions' angles instead of learning the robot's action types.
    ``clusterer`` clusters the images into views for each k (:data:`bootmap.views.CLUSTERERS`; the
    paper's k-means by default); ``learner`` is a name of :func:`bootmap.recognise.default_learners`
    whose cross-validated curve is reported beside nearest neighbour's (the paper's, which the checks use);
    by default the aligned discriminant, which holds up best as the laser's noise grows.
    A map that is not proved minimal in ``time_limit`` seconds is reported as such (with the best map
    found, if any) rather than raised: the report says what was and was not achieved.

    ``blas_threads`` caps the BLAS and OpenMP thread pools (threadpoolctl) for the run; None leaves them
    as they are. The images are small (a few hundred of 180 values): threads gain nothing, and when
    another process holds a core, OpenMP's threads wait on each other: clustering and recognition ran
    about 17 times slower (5 circuits of the notched rectangle: 4.2 s against 0.45 s in all, views 1.78 s
    against 0.11 s, recognition 2.17 s against 0.12 s).

    ``runs`` keeps the simulated run (:class:`~bootmap.experiments.runs.RunStore`): an experiment on the
    same world, noise, policy, length and seed reads it back instead of simulating it again (a sweep's
    cells that differ only in the learner, the levels, the action typing or the clusterer).
    """
    _check_choices(clusterer, learner)
    if blas_threads is None:
        return _run(world, circuits, steps, seed, out_dir, k_max, progress, time_limit, levels, quantum_deg,
                    clusterer, learner, policy, runs)
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=blas_threads):
        return _run(world, circuits, steps, seed, out_dir, k_max, progress, time_limit, levels, quantum_deg,
                    clusterer, learner, policy, runs)


def _check_choices(clusterer: str, learner: str) -> None:
    from ..recognise import default_learners
    from ..views import CLUSTERERS

    if clusterer not in CLUSTERERS:
        raise BadInput(f"unknown view clusterer {clusterer!r}; known: {', '.join(CLUSTERERS)}")
    if learner not in default_learners():
        raise BadInput(f"unknown learner {learner!r}; known: {', '.join(default_learners())}")


def _run(world, circuits, steps, seed, out_dir, k_max, progress, time_limit, levels, quantum_deg, view_method,
         learner, policy=None, runs: RunStore | None = None) -> dict:
    world = world if isinstance(world, World) else load_world(world)
    policy = policy or world.policy or "circuits"
    if policy not in POLICIES:
        raise BadInput(f"unknown policy {policy!r}; known: {', '.join(POLICIES)}")
    if circuits is not None and policy != "circuits":
        raise BadInput(f"{world.name} is explored (policy {policy}), not circled: give its run length as "
                       "steps (--steps), not circuits")
    if steps is None and circuits is None and policy in ("explore", "random"):
        steps = PAPER_EXPLORE_STEPS
    lap = Laps()
    timings = lap.timings
    circuits = circuits or PAPER_CIRCUITS

    def simulated():
        return simulate(world, policy=make_policy(policy, world, steps), circuits=circuits, steps=steps, seed=seed,
                        progress=progress)

    tableau = simulated() if runs is None else runs.simulated(world, policy, circuits, steps, seed, simulated)
    lap("simulate_s")
    images = np.array([s.image for s in tableau.steps], dtype=float)
    truth = [str(s.truth) for s in tableau.steps]
    clusterer = ViewClusterer(k_max=k_max, random_state=seed, max_range=world.laser.range_max,
                              method=view_method).fit(images, truth)
    views = view_labels(clusterer.labels_)
    lap("views_s")
    try:
        resolver = Resolver(time_limit=time_limit, levels=levels, quantum_deg=quantum_deg)
        cmap, map_note = resolver.resolve(tableau.with_views(views)), None
    except SolveTimeout as e:
        cmap, map_note = e.best_map, str(e)
    lap("map_s")
    if cmap is None:
        results = {"world": world.name, "seed": seed, "images": len(images), "clusterer": view_method,
                   "views": _views_section(clusterer, images, views, truth), "map": {"error": map_note},
                   "recognition": None, "timings": timings}
        results["checks"] = checks(results)
        if out_dir is not None:
            write_report(results, Path(out_dir), world, tableau, None)
        return results
    # The paper's labels: every image labelled by its *resolved* dstate.
    recognition = recognition_section(images, cmap.dstate_of, learner, seed)
    lap("recognise_s")
    results = {
        "world": world.name, "seed": seed, "images": len(images), "clusterer": view_method,
        "views": _views_section(clusterer, images, views, truth),
        "map": {**_map_section(cmap, truth, world), "proved_minimal": cmap.minimal, "note": map_note},
        "recognition": recognition,
        "timings": timings,
    }
    results["checks"] = checks(results)
    if out_dir is not None:
        write_report(results, Path(out_dir), world, tableau, cmap)
    return results


def recognition_section(images: np.ndarray, labels, learner: str = "1-NN", seed: int = 0) -> dict:
    """The paper's recognition, images labelled by their *resolved* dstates: the online curve and 10-fold
    cross-validated learning curves (nearest neighbour's, and ``learner``'s on the same folds, at the sizes of
    :data:`LEARNER_CURVE_SIZES` among them).

    The online curve takes any number of images. With too few images for the cross-validated curves
    (fewer than 12: the training folds then hold fewer than 10), their figures are empty lists and None,
    and ``cv_note`` says why; otherwise ``cv_note`` is None.
    """
    online = online_curve(images, labels)
    hits = online_hits(images, labels)
    section = {"online_accuracy": [float(x) for x in np.asarray(online)],
               "online_after_90": float(np.mean(hits[90:])) if len(hits) > 90 else None, "learner": learner}
    try:
        sizes = fitting_sizes(len(images), CURVE_SIZES)
    except TooFewImages as e:
        return {**section, "cv_sizes": [], "cv_mean": [], "cv_std": [], "cv_at_90": None,
                "learner_cv_sizes": [], "learner_cv_mean": [], "learner_cv_at_90": None,
                "cv_note": f"no learning curve: {e}"}
    cv = learning_curve_cv(images, labels, sizes=sizes, random_state=seed)
    # Another learner on the same folds (the paper's future work); nearest neighbour's curve is the paper's.
    if learner == "1-NN":
        other = cv
    else:
        other = learning_curve_cv(images, labels, sizes=[n for n in sizes if n in LEARNER_CURVE_SIZES],
                                  random_state=seed, learner=default_learners(seed)[learner])
    return {**section, "cv_sizes": [int(n) for n in cv.sizes], "cv_mean": [float(x) for x in cv.mean],
            "cv_std": [float(x) for x in cv.std], "cv_at_90": cv.at(90) if 90 in cv.sizes else None,
            "learner_cv_sizes": [int(n) for n in other.sizes], "learner_cv_mean": [float(x) for x in other.mean],
            "learner_cv_at_90": other.at(90) if 90 in other.sizes else None, "cv_note": None}


@dataclass(frozen=True)
class Check:
    """One thing the paper's experiment must show: a stable ``id`` (the key in ``results["checks"]``),
    the ``text`` a report prints, and ``holds``, which decides it on one run's results."""

    id: str
    text: str
    holds: Callable[[dict], bool]


def _k_by_m_is_largest_u1(r: dict) -> bool:
    # The internal measure picks the views that remove all image variability and no more (U is
    # computed against the true dstates); no k with U = 1 at all cannot show it.
    v = r["views"]
    return v["largest_k_with_U_1"] is not None and v["k"] == v["largest_k_with_U_1"]


def _map_is_true_topology(r: dict) -> bool:
    # As many dstates, places and paths as the world's truth, in a map proved minimal.
    m = r["map"]
    return "error" not in m and bool(m.get("proved_minimal")) and \
        (m["dstates"], m["places"], m["paths"]) == (m["true_dstates"], m["true_places"], m["true_paths"])


def _every_image_on_its_dstate(r: dict) -> bool:
    # 100% of images on the right dstate, up to renaming: no true dstates merged, none split.
    m = r["map"]
    return "error" not in m and m.get("dstate_accuracy") == 1.0


def _nn_at_90_at_least_target(r: dict) -> bool:
    # 10-fold cross-validated, images labelled by the map; a run too short to measure it does not show it.
    nn = (r["recognition"] or {}).get("cv_at_90")
    return nn is not None and nn >= NN_TARGET


# What the paper's experiment must show, in the order reports list it.
CHECKS = (
    Check("k_by_m_is_largest_u1", "k by M is the largest k with U = 1", _k_by_m_is_largest_u1),
    Check("map_is_true_topology", "map is the true topology", _map_is_true_topology),
    Check("every_image_on_its_dstate", "every image on its dstate", _every_image_on_its_dstate),
    Check("nn_at_90_at_least_85", f"nearest neighbour at 90 images >= {NN_TARGET:.0%}", _nn_at_90_at_least_target),
)
CHECK_TEXT = {c.id: c.text for c in CHECKS}


def checks(r: dict) -> dict[str, bool]:
    """What the paper's experiment must show, checked on one run's results: check id -> True or False.

    The ids and their sentences are :data:`CHECKS`:

    - ``k_by_m_is_largest_u1``: the internal measure picks the views that remove all image variability
      and no more (U is computed against the true dstates);
    - ``map_is_true_topology``: as many dstates, places and paths as the world's truth, proved minimal;
    - ``every_image_on_its_dstate``: 100% of images on the right dstate, up to renaming (so no true
      dstates merged, none split);
    - ``nn_at_90_at_least_85``: nearest neighbour at 90 images >= 85%, 10-fold cross-validated, images
      labelled by the map.
    """
    return {c.id: bool(c.holds(r)) for c in CHECKS}


def failed_checks(runs: list[dict]) -> list[str]:
    """The sentences of the checks that fail on any of the runs, in :data:`CHECKS` order."""
    return [c.text for c in CHECKS if any(not r["checks"].get(c.id, False) for r in runs)]


def _views_section(clusterer, images, views, truth) -> dict:
    return {"k": int(clusterer.k_), "ks": [int(k) for k in clusterer.ks_],
            "M": [float(x) for x in clusterer.internal_],
            "U": None if getattr(clusterer, "uncertainty_", None) is None else [float(x) for x in clusterer.uncertainty_],
            "largest_k_with_U_1": clusterer.largest_k_with_u1_,
            "table": jsonable(view_table(images, views)), "labels": views,
            "truth": list(truth)}  # the true dstate of every image (evaluation only)


def _map_section(cmap, truth, world) -> dict:
    merged, split = defaultdict(set), defaultdict(set)
    for t, d in zip(truth, cmap.dstate_of):
        merged[d].add(t)
        split[t].add(d)
    return {"dstates": cmap.n_dstates, "places": cmap.n_places, "paths": cmap.n_paths, "unique": cmap.unique,
            "true_dstates": len(set(truth)), "true_places": len(world.places), "true_paths": len(world.paths),
            "dstate_accuracy": dstate_accuracy(truth, cmap.dstate_of),
            # Say which true dstates the map could not tell apart, rather than claim success.
            "merged_true_dstates": {d: sorted(ts) for d, ts in merged.items() if len(ts) > 1},
            # ... and which true dstates it took for several.
            "split_true_dstates": {t: sorted(ds) for t, ds in split.items() if len(ds) > 1},
            "solve_s": cmap.stats.total_s}


def jsonable(x):
    """``x`` with numpy arrays and scalars as lists and numbers, and keys as strings: what ``json`` writes
    (an experiment's results.json, a log experiment's too)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    return x


def write_report(results: dict, out: Path, world, tableau, cmap) -> None:
    """results.json, report.md and the figures."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    _figures(results, out, world, tableau)
    (out / "report.md").write_text(_report_text(results))


def _figures(results: dict, out: Path, world, tableau) -> None:
    from ..sim.render import render

    render(world, tableau, path=out / "world_map.png", title=f"{results['world']}: run and true dstates")
    views_figure(results, out / "views_M_U.png")
    if results["recognition"] is not None:
        curves_figure(results, out / "learning_curves.png")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def views_figure(results: dict, path: Path) -> None:
    """M and U(V|S) against k (the paper's Figure 3); U against shuffled dstates too where the results
    have it (``views.U_shuffled``), and the k each criterion chose."""
    plt = _pyplot()
    v = results["views"]
    fig, axes = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
    axes[0].plot(v["ks"], v["M"], "o-")
    axes[0].axvline(v.get("k_by_M", v["k"]), color="grey", ls=":", label=f"k by M = {v.get('k_by_M', v['k'])}")
    if v.get("k_by_davies_bouldin") is not None:
        axes[0].axvline(v["k_by_davies_bouldin"], color="tab:red", ls="--",
                        label=f"k by Davies-Bouldin = {v['k_by_davies_bouldin']}")
    axes[0].legend(fontsize=8)
    axes[0].set_ylabel("internal measure M")
    if v["U"] is not None:
        axes[1].plot(v["ks"], v["U"], "o-", label="U(V|S), true dstates")
    if v.get("U_shuffled") is not None:
        axes[1].plot(v["ks"], v["U_shuffled"], "s--", color="grey", label="U(V|S), dstates shuffled")
        axes[1].legend(fontsize=8)
    axes[1].set_ylabel("U(V|S)")
    axes[1].set_xlabel("k")
    fig.suptitle(f"{results['world']}: clustering images into views (paper Figure 3)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def curves_figure(results: dict, path: Path) -> None:
    """The online and cross-validated learning curves (the paper's Figure 4)."""
    plt = _pyplot()
    rec = results["recognition"]
    online = rec["online_accuracy"]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(range(1, len(online) + 1), online, label="online, cumulative (predict, then store)")
    ax.errorbar(rec["cv_sizes"], rec["cv_mean"], yerr=rec["cv_std"], fmt="o-", capsize=3,
                label="10-fold cross-validation")
    ax.set_xlabel("images experienced")
    ax.set_ylabel("accuracy")
    ax.set_ylim(0, 1.02)
    ax.legend()
    fig.suptitle(f"{results['world']}: recognising dstates from images (paper Figure 4)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _report_text(r: dict) -> str:
    m, v, rec = r["map"], r["views"], r["recognition"]
    lines = [f"# {r['world']}, seed {r['seed']}", "",
             f"{r['images']} images. k chosen by M: **{v['k']}**; largest k with U = 1: {v['largest_k_with_U_1']}.", ""]
    lines += ["| view | images | left (m) | front (m) | right (m) |", "|---|---|---|---|---|"]
    lines += [f"| {row['view']} | {row['n']} | {row['left']:.2f} | {row['front']:.2f} | {row['right']:.2f} |"
              for row in v["table"]]
    lines += ["", "![M and U against k](views_M_U.png)", ""]
    if "error" in m:
        lines += [f"**No map**: {m['error']}", ""]
    else:
        if not m["proved_minimal"]:
            lines += [f"**The map below is not proved minimal**: {m['note']}", ""]
        lines += [f"Map: {m['dstates']} dstates, {m['places']} places, {m['paths']} paths "
                  f"(truth: {m['true_dstates']}, {m['true_places']}, {m['true_paths']}); "
                  f"dstate accuracy {m['dstate_accuracy']:.1%} up to renaming; unique: {m['unique']}.", ""]
        if m["merged_true_dstates"]:
            lines += ["**The map could not tell these true dstates apart** (map dstate: true dstates): " +
                      "; ".join(f"{d}: {', '.join(ts)}" for d, ts in m["merged_true_dstates"].items()), ""]
        if m.get("split_true_dstates"):
            lines += ["**The map took these true dstates for several** (true dstate: map dstates): " +
                      "; ".join(f"{t}: {', '.join(ds)}" for t, ds in m["split_true_dstates"].items()), ""]
    if rec is not None and rec["cv_at_90"] is not None:
        lines += [f"Nearest neighbour, images labelled by the resolved dstates: {rec['cv_at_90']:.1%} at 90 "
                  f"images (10-fold cross-validation); online, once 90 images are stored: "
                  f"{rec['online_after_90']:.1%}." + _beside(rec), "", "![learning curves](learning_curves.png)", ""]
    elif rec is not None and rec.get("cv_note"):
        lines += [f"Recognition: {rec['cv_note']}.", ""]
    lines += _checks_text([r])
    lines += ["![the run](world_map.png)", "", f"Timings (s): {r['timings']}", ""]
    return "\n".join(lines)


def other_learner(rec: dict) -> tuple[str, float] | None:
    """The learner reported beside nearest neighbour and its accuracy at 90 images, on the same folds;
    None when it is nearest neighbour itself, or has no figure at 90."""
    if rec.get("learner", "1-NN") == "1-NN" or rec.get("learner_cv_at_90") is None:
        return None
    return rec["learner"], rec["learner_cv_at_90"]


def _beside(rec: dict) -> str:
    other = other_learner(rec)
    return "" if other is None else f" {other[0]} on the same folds: {other[1]:.1%}."


def _checks_text(runs: list[dict]) -> list[str]:
    """The paper's must-show figures, checked: what holds on every run, and where what does not."""
    lines = ["## What the paper's experiment must show", ""]
    for check in CHECKS:
        failed = [r["seed"] for r in runs if not r["checks"][check.id]]
        if not failed:
            where = "yes" if len(runs) == 1 else f"yes, on every seed ({len(runs)})"
        else:
            where = "**no**" if len(runs) == 1 else f"**no** on seed(s) {', '.join(map(str, failed))}"
        lines.append(f"- {check.text}: {where}")
    ok = not failed_checks(runs)
    lines += ["", "All of it holds." if ok and len(runs) == 1 else
              "All of it holds on every seed." if ok else "**Not everything holds** (above).", ""]
    return lines


def run_seeds(world: str | World, seeds: list[int], out_dir: str | Path | None = None, progress: bool = False,
              **kwargs) -> dict:
    """The experiment once per seed (each in ``out_dir/seed_N``), and the mean and spread over seeds.
    A seed whose run fails (the simulated robot gets stuck, say) is recorded with its error, and the
    other seeds run; ``progress`` shows a bar over the seeds.

    Returns ``{"world", "seeds", "runs": [results...], "summary": {figure: {"mean", "std", "min", "max"}}}``
    and writes ``summary.json`` and ``summary.md`` when ``out_dir`` is given.
    """
    world = world if isinstance(world, World) else load_world(world)
    runs = []
    for s in _over(seeds, progress):
        try:
            runs.append(run_experiment(world, seed=s, out_dir=None if out_dir is None else Path(out_dir) / f"seed_{s}",
                                       **kwargs))
        except BadInput:
            raise  # the same for every seed: say it once
        except BootmapError as e:  # e.g. the simulated robot got stuck: record it, run the other seeds
            runs.append(_failed_run(world, s, e))
    summary = {name: _spread([f(r) for r in runs]) for name, f in _FIGURES.items()}
    out = {"world": world.name, "seeds": list(seeds), "runs": runs, "summary": summary}
    if out_dir is not None:
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        (Path(out_dir) / "summary.json").write_text(json.dumps(out, indent=1))
        (Path(out_dir) / "summary.md").write_text(_summary_text(out))
    return out


def _over(seeds: list[int], progress: bool):
    if not progress:
        return seeds
    import sys

    from tqdm import tqdm

    return tqdm(seeds, unit="seed", file=sys.stderr, dynamic_ncols=True, desc="seeds")


def _failed_run(world: World, seed: int, e: BootmapError) -> dict:
    """A seed whose run failed, as a run record: every figure missing, every check false."""
    return {"world": world.name, "seed": seed, "error": f"{type(e).__name__}: {e}", "images": 0, "views": None,
            "map": {"error": str(e)}, "recognition": None, "checks": {c.id: False for c in CHECKS}, "timings": {}}


# The figures compared across seeds; None where a run has no map.
_FIGURES = {
    "k by M": lambda r: (r["views"] or {}).get("k"),
    "largest k with U = 1": lambda r: (r["views"] or {}).get("largest_k_with_U_1"),
    "dstates": lambda r: r["map"].get("dstates"),
    "places": lambda r: r["map"].get("places"),
    "paths": lambda r: r["map"].get("paths"),
    "dstate accuracy": lambda r: r["map"].get("dstate_accuracy"),
    "1-NN at 90 images (CV)": lambda r: (r["recognition"] or {}).get("cv_at_90"),
}


# What the paper reports for its two environments, by figure ("-" where it gives no number).
PAPER_FIGURES = {
    "notched_rectangle": {"images": "400 (50 circuits)", "k by M": "4", "largest k with U = 1": "4",
                          "dstates": "8", "places": "4", "paths": "4", "dstate accuracy": "-",
                          "1-NN at 90 images (CV)": "about 0.9"},
    "taylor_hall": {"images": "100", "k by M": "8", "largest k with U = 1": "8", "dstates": "20",
                    "places": "7", "paths": "4", "dstate accuracy": "1 (all 20 dstates told apart)",
                    "1-NN at 90 images (CV)": "0.88"},
}


def _spread(values: list) -> dict:
    known = [float(v) for v in values if v is not None]
    if not known:
        return {"values": values, "mean": None, "std": None, "min": None, "max": None}
    return {"values": values, "mean": float(np.mean(known)), "std": float(np.std(known)),
            "min": min(known), "max": max(known)}


def _summary_text(out: dict) -> str:
    paper = PAPER_FIGURES.get(out["world"], {})
    lines = [f"# {out['world']}: seeds {', '.join(map(str, out['seeds']))}", "",
             "| figure | paper | per seed | mean | spread (min - max) |", "|---|---|---|---|---|",
             f"| images | {paper.get('images', '-')} | {', '.join(str(r['images']) for r in out['runs'])} | | |"]
    for name, s in out["summary"].items():
        per_seed = ", ".join("-" if v is None else f"{v:.3g}" for v in s["values"])
        mean = "-" if s["mean"] is None else f"{s['mean']:.3g}"
        spread = "-" if s["min"] is None else f"{s['min']:.3g} - {s['max']:.3g}"
        lines.append(f"| {name} | {paper.get(name, '-')} | {per_seed} | {mean} | {spread} |")
    lines += [""] + _checks_text(out["runs"])
    return "\n".join(lines) + "\n"
