"""Figures of a log experiment, drawn over the log's true poses (which the learning never saw).

- :func:`trajectory_figure`: the true path in grey, each chosen dstate at its true pose, coloured by
  the place the map put it in (black crosses where there is no map).
- :func:`precision_recall_figure`: place recognition's precision-recall curve, one per descriptor.
- :func:`topological_figure`: the learned topological map, each place drawn at the mean true position
  of the dstates the map put in it, its paths as lines through their places in order.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _poses(tableau) -> np.ndarray:
    return np.array([s.pose for s in tableau.steps], dtype=float)


def trajectory_figure(results: dict, tableau, cmap, path: Path) -> None:
    """The true trajectory and the chosen dstates, coloured by learned place."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 7))
    track = np.asarray(tableau.meta.get("trajectory", []), dtype=float).reshape(-1, 2)
    ax.plot(track[:, 0], track[:, 1], color="0.8", lw=0.8, label="true path")
    poses = _poses(tableau)
    if cmap is None:
        ax.plot(poses[:, 0], poses[:, 1], "kx", label="dstates (no map)")
    else:
        places = sorted(set(cmap.place_of.values()))
        index = {p: i for i, p in enumerate(places)}
        colour = [index[cmap.place_of.get(d)] if d in cmap.place_of else -1 for d in cmap.dstate_of]
        ax.scatter(poses[:, 0], poses[:, 1], c=colour, cmap="tab20", s=25, zorder=3,
                   label=f"dstates, coloured by learned place ({len(places)})")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, true)")
    ax.set_ylabel("y (m, true)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"{results['world']}: dstates at their true poses, by learned place")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def place_positions(tableau, cmap) -> dict[str, np.ndarray]:
    """Each learned place's mean true position (over the visits to its dstates)."""
    poses = _poses(tableau)
    at: dict[str, list[np.ndarray]] = {}
    for step, d in enumerate(cmap.dstate_of):
        if d in cmap.place_of:
            at.setdefault(cmap.place_of[d], []).append(poses[step, :2])
    return {p: np.mean(xy, axis=0) for p, xy in at.items()}


def topological_figure(results: dict, tableau, cmap, path: Path) -> None:
    """The learned places at their mean true positions, joined along the learned paths."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 7))
    track = np.asarray(tableau.meta.get("trajectory", []), dtype=float).reshape(-1, 2)
    ax.plot(track[:, 0], track[:, 1], color="0.9", lw=0.8)
    where = place_positions(tableau, cmap)
    for places in cmap.paths.values():
        xy = np.array([where[p] for p in places if p in where])
        if len(xy) > 1:
            ax.plot(xy[:, 0], xy[:, 1], "-", lw=1.5, alpha=0.7)
    xy = np.array(list(where.values()))
    ax.plot(xy[:, 0], xy[:, 1], "ko", ms=4, zorder=3)
    for name, (x, y) in where.items():
        ax.annotate(name, (x, y), fontsize=6, xytext=(2, 2), textcoords="offset points")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, true)")
    ax.set_ylabel("y (m, true)")
    m = results["map"]
    ax.set_title(f"{results['world']}: learned map, {m['places']} places and {m['paths']} paths "
                 "at their mean true positions", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def precision_recall_figure(results: dict, path: Path) -> None:
    """Place recognition's precision against recall, a curve per descriptor (a point per threshold),
    the 95% precision line dashed."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for name, p in results["place_recognition"].items():
        recall = [c["recall"] for c in p["curve"]]
        precision = [c["precision"] for c in p["curve"]]
        at95 = "-" if p["recall_at_95_precision"] is None else f"{p['recall_at_95_precision']:.2f}"
        ax.plot(recall, precision, "-o", ms=3, label=f"{name} (recall at 95% precision {at95})")
    ax.axhline(0.95, color="0.6", ls="--", lw=0.8)
    ax.set_xlim(0, 1.02)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("recall (visits with a true revisit)")
    ax.set_ylabel("precision")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"{results['world']}: place recognition, best earlier match", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
