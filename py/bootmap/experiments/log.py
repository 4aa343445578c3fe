"""The paper's experiment on a robot's log: ingest -> views -> map -> recognise, judged by the log's poses.

1. The log is read and cut into dstates where odometry turns (:mod:`bootmap.ingest.ingest`); the log's
   true poses give the true dstates (:mod:`bootmap.ingest.truth`), used only to evaluate.
2. Images are clustered into views as in the simulated experiment; k by the paper's M and, since M
   falls steadily with k on real scans (it picks k = 1 or 2 there), by the Davies-Bouldin index, which
   does not (:func:`bootmap.views.davies_bouldin_k`). Both are reported; the map uses ``view_criterion``'s.
3. The tableau is resolved into dstates, places and paths: by default by loop closing
   (:class:`~bootmap.mapping.loops.LoopCloser`: odometry proposes which visits are one dstate, every
   axiom checks), since the log's views barely tell dstates apart and the paper's fewest dstates
   (``mapper="fewest"``, :class:`~bootmap.mapping.resolver.Resolver`) then merge what they merely fail
   to tell apart.
4. A baseline without images: dstates from dead-reckoned poses alone (local metrical consistency).
5. Recognition as the paper's (images labelled by the map), and nearest neighbour on the true dstates
   seen more than once, with raw scans and with a shift-tolerant distance (:mod:`bootmap.experiments.evaluate`).

Results use the simulated experiment's keys where the meaning is the same (``views``, ``map``,
``recognition``, ``timings``), and add ``truth`` (corner recall), ``nn_revisited`` and ``targets``
(the targets this project set itself for a real log, measured, never assumed).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import BadInput, LogError, SolveTimeout
from .world import Laps, curves_figure, jsonable, recognition_section, views_figure
from ..mapping.api import Mapper
from ..mapping.loops import MAPPERS
from ..metrics import dstate_accuracy
from ..views import ViewClusterer, davies_bouldin_k, view_labels, view_table
from ..ingest.dstates import JunctionDetector, TurnDetector
from .evaluate import DESCRIPTORS, dead_reckoned_dstates, map_against_truth, nn_on_revisits, views_against_truth
from ..ingest.ingest import log_tableau, read_log, travel_ends, turn_ends

#: How k is chosen for the map's views: "auto" takes M's k unless M degenerates (k <= 2), then
#: Davies-Bouldin's.
VIEW_CRITERIA = ("auto", "M", "davies-bouldin")
#: The targets this project set itself for a real log (set from an outside probe of the Killian log;
#: ambitious).
TARGETS = {"corner_recall": 0.95, "angles_within_10_deg": 1.0, "visits_in_true_dstate": 0.80,
           "nn_revisited": 0.60}


def run_log_experiment(log: str | Path, out_dir: str | Path | None = None, seed: int = 0, k_max: int = 12,
                       time_limit: float = 60.0, quantum_deg: float | None = None,
                       view_criterion: str = "auto", detector: TurnDetector = TurnDetector(),
                       max_range: float = 20.0, radius_m: float = 3.0, progress: bool = False,
                       junctions: JunctionDetector | None = None, mapper: str = "loops") -> dict:
    """Run the experiment on a log (a path any of :func:`~bootmap.ingest.ingest.read_log`'s formats, or
    ``killian``); see the module docstring. Returns the results and, given ``out_dir``, writes
    ``results.json``, ``report.md`` and figures there. The robot's action types are learned, as in the
    simulated experiment, unless ``quantum_deg`` rounds the angles instead."""
    if view_criterion not in VIEW_CRITERIA:
        raise BadInput(f"unknown view criterion {view_criterion!r}; known: {', '.join(VIEW_CRITERIA)}")
    if mapper not in MAPPERS:
        raise BadInput(f"unknown mapper {mapper!r}; known: {', '.join(MAPPERS)}")
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):  # small arrays: threads only wait on each other (see run_experiment)
        return _run(log, out_dir, seed, k_max, time_limit, quantum_deg, view_criterion, detector, max_range,
                    radius_m, progress, junctions, mapper)


def _run(log, out_dir, seed, k_max, time_limit, quantum_deg, view_criterion, detector, max_range, radius_m,
         progress, junctions, mapper) -> dict:
    lap = Laps()
    timings = lap.timings
    scans = read_log(log, progress=progress)
    tableau = log_tableau(scans, detector, max_range=max_range, radius_m=radius_m, source=str(log),
                          junctions=junctions)
    if any(s.truth is None for s in tableau.steps):
        raise LogError("the log has no true poses (g2o vertices, CARMEN robot poses or a ROS --truth-topic): "
                       "nothing to evaluate the map against", str(log))
    lap("ingest_s")
    images = np.array([s.image for s in tableau.steps], dtype=float)
    truth = [str(s.truth) for s in tableau.steps]
    clusterer, views_section = _views(images, truth, k_max, seed, max_range, view_criterion)
    views = view_labels(clusterer.labels_per_k_[views_section["k"]])
    views_section.update(table=jsonable(view_table(images, views)), labels=views)
    lap("views_s")
    mapped = tableau.with_views(views)
    try:
        cmap, map_note = Mapper(time_limit=time_limit, quantum_deg=quantum_deg, how=mapper).map(mapped), None
    except SolveTimeout as e:
        cmap, map_note = e.best_map, str(e)
    lap("map_s")
    nn = {d: nn_on_revisits(images, truth, d) for d in DESCRIPTORS}
    odometry = [s.odometry for s in scans]
    dead = dead_reckoned_dstates([odometry[i] for i in tableau.meta["dstates"]["scans"]], odometry, radius_m,
                                 turn_ends(tableau.actions), travel_ends(tableau.actions))
    recognition = None if cmap is None else recognition_section(images, cmap.dstate_of, "1-NN", seed)
    lap("recognise_s")
    results = {
        "world": _name(log), "log": str(log), "seed": seed, "scans": len(scans), "images": len(images),
        "clusterer": "kmeans", "quantum_deg": quantum_deg,
        "truth": {**tableau.meta["truth"], "true_dstates": len(set(truth))},
        "views": views_section,
        "map": {"error": map_note} if cmap is None else
               {**map_against_truth(truth, cmap), "found_by": cmap.found_by, "proved_minimal": cmap.minimal,
                "misreads": len(cmap.suspect_steps), "note": map_note,
                "retyped_steps": cmap.retyped_steps},
        "dead_reckoning": {"dstates": len(set(dead)), "dstate_accuracy": dstate_accuracy(truth, dead)},
        "recognition": recognition, "nn_revisited": nn, "timings": timings}
    results["targets"] = targets(results)
    if out_dir is not None:
        write_log_report(results, Path(out_dir), tableau, cmap)
    return results


def _name(log) -> str:
    return "killian" if str(log) == "killian" else Path(str(log)).name


def _views(images, truth, k_max, seed, max_range, criterion) -> tuple[ViewClusterer, dict]:
    """Views by M and by Davies-Bouldin; ``k`` is the one the map uses. ``k_note`` says where the data
    allowed less than asked: k capped below ``k_max``, or the Davies-Bouldin index defined at no k."""
    clusterer = ViewClusterer(k_max=k_max, random_state=seed, max_range=max_range).fit(images, truth)
    k_db, db = davies_bouldin_k(clusterer, images)
    degenerate = clusterer.k_ <= 2
    use_db = k_db is not None and (criterion == "davies-bouldin" or (criterion == "auto" and degenerate))
    k = k_db if use_db else clusterer.k_
    section = {"k": int(k), "criterion": "davies-bouldin" if use_db else "M", "k_by_M": int(clusterer.k_),
               "k_max": int(k_max), "k_note": _k_note(len(images), int(clusterer.ks_[-1]), k_max, k_db),
               "M_degenerate": degenerate, "k_by_davies_bouldin": k_db, "davies_bouldin": db,
               "ks": [int(x) for x in clusterer.ks_], "M": [float(x) for x in clusterer.internal_],
               "U": [float(x) for x in clusterer.uncertainty_],
               "largest_k_with_U_1": clusterer.largest_k_with_u1_,
               **views_against_truth(clusterer, truth, seed), "truth": list(truth)}
    return clusterer, section


def _k_note(n_images: int, k_tried: int, k_max: int, k_db: int | None) -> str | None:
    """What the images allowed of the k sweep, when less than asked; None when it ran as asked."""
    notes = []
    if k_tried < k_max:
        notes.append(f"k capped at {k_tried}, below k_max {k_max}: {n_images} images, {k_tried} of them "
                     "distinct")
    if k_db is None:
        notes.append(f"no k by Davies-Bouldin: its index needs 2 to (images - 1) views, none of the k tried "
                     f"(1..{k_tried}) on {n_images} images")
    return "; ".join(notes) or None


def targets(r: dict) -> dict:
    """The targets, each with what was measured and whether it is met."""
    recall = r["truth"]["corner_recall"]
    m = r["map"]
    measured = {"corner_recall": recall["recall"], "angles_within_10_deg": recall["angles_within_10_deg"],
                "visits_in_true_dstate": m.get("dstate_accuracy"),
                "nn_revisited": max((n["revisited"] for n in r["nn_revisited"].values()
                                     if n["revisited"] is not None), default=None)}
    return {name: {"target": goal, "measured": measured[name],
                   "met": measured[name] is not None and measured[name] >= goal}
            for name, goal in TARGETS.items()}


def headline(r: dict) -> list[str]:
    """The lines ``bootmap experiment --log`` prints."""
    v, m, t = r["views"], r["map"], r["truth"]
    lines = [f"{r['world']}: {r['scans']} scans, {r['images']} dstates chosen; turns at "
             f"{t['corner_recall']['found']} of {t['corner_recall']['corners']} corners; truth: "
             f"{t['true_dstates']} true dstates"]
    note = " (M degenerates: views by Davies-Bouldin)" if v["criterion"] == "davies-bouldin" else ""
    lines.append(f"  views: k = {v['k_by_M']} by M, {v['k_by_davies_bouldin']} by Davies-Bouldin; "
                 f"map uses k = {v['k']}{note}; U(V|S) {v['U'][v['k'] - 1]:.3f} against "
                 f"{v['U_shuffled'][v['k'] - 1]:.3f} with dstates shuffled")
    if v.get("k_note"):
        lines.append(f"  views: {v['k_note']}")
    if "error" in m:
        lines.append(f"  map: none ({m['error']})")
    else:
        lines.append(f"  map ({m['found_by']}): {m['dstates']} dstates, {m['places']} places, {m['paths']} paths (truth "
                     f"{m['true_dstates']} dstates, {m['true_places']} places); visits in their true dstate: "
                     f"{m['dstate_accuracy']:.1%} (a dstate per visit: {m['every_visit_own_dstate_accuracy']:.1%})")
    if (r["recognition"] or {}).get("cv_note"):
        lines.append(f"  recognition: {r['recognition']['cv_note']}")
    dead = r["dead_reckoning"]
    lines.append(f"  odometry alone (dead-reckoned places within the radius, no image): {dead['dstates']} dstates, "
                 f"{dead['dstate_accuracy']:.1%} of visits in their true dstate")
    for d, n in r["nn_revisited"].items():
        if n["revisited"] is None:
            lines.append(f"  nearest neighbour ({d} scans): no true dstate is seen twice")
            continue
        lines.append(f"  nearest neighbour ({d} scans) on revisited dstates: {n['revisited']:.1%} of "
                     f"{n['revisited_visits']} visits; on all visits {n['all_visits']:.1%} (ceiling "
                     f"{n['ceiling']:.1%})")
    return lines


def write_log_report(results: dict, out: Path, tableau, cmap) -> None:
    """results.json, report.md and the figures of a log experiment."""
    from .figures import topological_figure, trajectory_figure

    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(jsonable(results), indent=1))
    views_figure(results, out / "views_M_U.png")
    trajectory_figure(results, tableau, cmap, out / "trajectory.png")
    if cmap is not None:
        topological_figure(results, tableau, cmap, out / "topological_map.png")
        curves_figure(results, out / "learning_curves.png")
    (out / "report.md").write_text(_report_text(results, cmap is not None))


def _report_text(r: dict, has_map: bool) -> str:
    lines = [f"# {r['world']}: the experiment on a robot's log", "", "```", *headline(r), "```", ""]
    lines += ["## Targets", "", "| figure | target | measured | met |", "|---|---|---|---|"]
    for name, t in r["targets"].items():
        measured = "-" if t["measured"] is None else f"{t['measured']:.1%}"
        lines.append(f"| {name} | {t['target']:.0%} | {measured} | {'yes' if t['met'] else 'no'} |")
    lines += ["", "![M and U against k](views_M_U.png)", "", "![trajectory](trajectory.png)", ""]
    if has_map:
        lines += ["![topological map](topological_map.png)", "", "![learning curves](learning_curves.png)", ""]
    lines += [f"Timings (s): {r['timings']}", ""]
    return "\n".join(lines)
