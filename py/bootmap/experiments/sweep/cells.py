"""One cell of a sweep: an experiment run as ``bootmap experiment`` runs it, reduced to a row of the table.

:func:`run_cell` never raises: a cell whose experiment fails (the simulated robot gets stuck, a bug), runs
over its ``cell_timeout`` or dies (killed by the kernel for memory, say) comes back as a row with its
``status`` and ``error``, and the sweep goes on. The experiment runs in a child forked for the cell, so
that a cell over its time can be stopped for sure (clingo cannot be interrupted inside a grounding, and
Dask runs tasks in threads, where no signal reaches them) and whatever it leaves behind dies with it.
Everything clingo builds is built inside the child: a Control does not pickle and never has to.
"""

from __future__ import annotations

import os
import socket
import time

from ...proc import in_child
from .spec import Cell

#: The columns of the results table, in order. ``TIMING_COLUMNS`` vary from run to run (and machine to
#: machine); every other column is determined by the cell.
COLUMNS = ("cell_id", "world", "seed", "noise", "clusterer", "learner", "levels", "quantum", "status", "error",
           "images", "k", "largest_k_with_U_1", "U_at_k", "dstates", "places", "paths", "true_dstates",
           "true_places", "true_paths", "proved_minimal", "map_exact", "dstate_accuracy", "nn_at_90",
           "learner_at_90", "online_after_90", "k_by_m_is_largest_u1", "map_is_true_topology",
           "every_image_on_its_dstate", "nn_at_90_at_least_85", "all_checks",
           "nn_revisited", "nn_revisited_shift", "dead_reckoning_accuracy",
           "seconds", "simulate_s", "ingest_s", "views_s", "map_s", "recognise_s", "worker")
TIMING_COLUMNS = ("seconds", "simulate_s", "ingest_s", "views_s", "map_s", "recognise_s", "worker")
CHECK_COLUMNS = ("k_by_m_is_largest_u1", "map_is_true_topology", "every_image_on_its_dstate",
                 "nn_at_90_at_least_85")


def run_cell(cell: Cell) -> dict:
    """Run ``cell``'s experiment (in a forked child, stopped at ``cell.cell_timeout``) -> its row."""
    start = time.perf_counter()
    outcome = in_child(lambda: _experiment_row(cell), cell.cell_timeout)
    kind, payload = outcome[0], outcome[1]
    if kind == "ok":
        row = payload
    else:
        row = failed_row(cell, kind, f"cell timeout: {payload}" if kind == "timeout" else payload)
    row["seconds"] = round(time.perf_counter() - start, 3)
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return row


def failed_row(cell: Cell, status: str, error: str) -> dict:
    """The row of a cell that did not finish: its axes, ``status`` (``failed`` or ``timeout``) and error."""
    return _row(cell, status, error)


def _row(cell: Cell, status: str, error: str | None) -> dict:
    """A row with the cell's axes, its status and error, no figures and the paper's checks not met."""
    row = {c: None for c in COLUMNS}
    row.update(_axes(cell), status=status, error=error, all_checks=False)
    row.update({c: False for c in CHECK_COLUMNS})
    row["settings"] = dict(cell.noise.settings)
    return row


def _axes(cell: Cell) -> dict:
    return {"cell_id": cell.id, "world": cell.world, "seed": cell.seed, "noise": cell.noise.name,
            "clusterer": cell.clusterer, "learner": cell.learner, "levels": cell.levels_text,
            "quantum": cell.quantum_text}


def _experiment_row(cell: Cell) -> dict:
    """The experiment itself (in the child) and its row; the learning curves ride along for the figures."""
    from ...errors import BootmapError
    from ..runs import RunStore
    from ..world import run_experiment
    from ...sim.world import loads_world

    if cell.log is not None:
        return _log_row(cell)
    try:
        world = loads_world(cell.world_text, cell.world_path, dict(cell.noise.settings))
        r = run_experiment(world, circuits=cell.circuits, steps=cell.steps, seed=cell.seed, k_max=cell.k_max,
                           time_limit=cell.time_limit, levels=None if cell.levels is None else list(cell.levels),
                           quantum_deg=cell.quantum_deg, clusterer=cell.clusterer, learner=cell.learner,
                           runs=None if cell.runs_dir is None else RunStore(cell.runs_dir))
    except BootmapError as e:  # e.g. the robot got stuck: the cell's result, not a crash
        return failed_row(cell, "failed", f"{type(e).__name__}: {e}")
    return experiment_row(cell, r)


def experiment_row(cell: Cell, r: dict) -> dict:
    """One experiment's results (``run_experiment``'s dict) as a row of the sweep's table."""
    v, m, rec = r["views"], r["map"], r["recognition"] or {}
    has_map = "error" not in m
    u = None if v.get("U") is None else v["U"][v["ks"].index(v["k"])]
    row = {c: None for c in COLUMNS}
    row.update(_axes(cell))
    row.update(
        status="ok", error=None if has_map else f"no map: {m['error']}", images=r["images"], k=v["k"],
        largest_k_with_U_1=v["largest_k_with_U_1"], U_at_k=None if u is None else round(u, 6),
        proved_minimal=bool(m.get("proved_minimal")) if has_map else False,
        map_exact=bool(r["checks"]["map_is_true_topology"] and r["checks"]["every_image_on_its_dstate"]),
        nn_at_90=_round(rec.get("cv_at_90")), learner_at_90=_round(rec.get("learner_cv_at_90")),
        online_after_90=_round(rec.get("online_after_90")), all_checks=all(r["checks"].values()),
        **{c: bool(r["checks"][c]) for c in CHECK_COLUMNS}, **r["timings"])
    if has_map:
        row.update({k: m[k] for k in ("dstates", "places", "paths", "true_dstates", "true_places", "true_paths")},
                   dstate_accuracy=round(m["dstate_accuracy"], 6))
    row["settings"] = dict(cell.noise.settings)
    if rec:
        row["curve"] = {"sizes": rec["cv_sizes"], "nn": [round(x, 6) for x in rec["cv_mean"]],
                        "learner_sizes": rec.get("learner_cv_sizes", rec["cv_sizes"]),
                        "learner": [round(x, 6) for x in rec["learner_cv_mean"]]}
    return row


def _log_row(cell: Cell) -> dict:
    """The experiment on a robot's log (``bootmap experiment --log``) and its row: the map against the
    log's poses, nearest neighbour on revisited dstates, the dead-reckoning baseline. The paper's checks,
    made for the simulator's worlds, are not taken (False)."""
    from ...errors import BootmapError
    from ..log import run_log_experiment

    try:
        r = run_log_experiment(cell.log, seed=cell.seed, k_max=cell.k_max, time_limit=cell.time_limit,
                               quantum_deg=cell.quantum_deg, perfect_odometry=False)
    except BootmapError as e:
        return failed_row(cell, "failed", f"{type(e).__name__}: {e}")
    v, m, rec, nn = r["views"], r["map"], r["recognition"] or {}, r["nn_revisited"]
    has_map = "error" not in m
    row = _row(cell, "ok", None if has_map else f"no map: {m['error']}")
    row.update(images=r["images"], k=v["k"], largest_k_with_U_1=v["largest_k_with_U_1"],
               U_at_k=round(v["U"][v["k"] - 1], 6), nn_at_90=_round(rec.get("cv_at_90")),
               nn_revisited=_round(nn["raw"]["revisited"]), nn_revisited_shift=_round(nn["shift"]["revisited"]),
               dead_reckoning_accuracy=_round(r["dead_reckoning"]["dstate_accuracy"]),
               true_dstates=r["truth"]["true_dstates"], map_exact=False,
               **{k: v for k, v in r["timings"].items() if k in TIMING_COLUMNS})
    if has_map:
        row.update({k: m[k] for k in ("dstates", "places", "paths", "true_places")},
                   proved_minimal=bool(m["proved_minimal"]), dstate_accuracy=round(m["dstate_accuracy"], 6),
                   map_exact=m["dstate_accuracy"] == 1.0 and m["places"] == m["true_places"])
    return row


def _round(x: float | None) -> float | None:
    return None if x is None else round(float(x), 6)
