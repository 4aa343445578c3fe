"""Drawing a world and a run with matplotlib (Agg, no display): beside the simulation, never inside it.

:func:`render` draws the walls, clutter and ground-truth places of a world; given a tableau from the
simulator, also the robot's trajectory and its dstates - one arrow per true dstate at the mean pose of
its images, numbered in the order the robot first reached them - and, optionally, one step's image as
the laser rays it was.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon, Rectangle

from ..tableau import Tableau
from .world import World

CLUTTER_COLOURS = {"lockers": "#8c9fb5", "bench": "#b59a72", "desk": "#a7845a", "blackboard": "#3b4a3f",
                   "trash can": "#7a7a7a"}


def render(world: World, tableau: Tableau | None = None, image_step: int | None = None,
           path: str | Path | None = None, title: str | None = None) -> Figure:
    """Draw ``world`` (and a run) and, if ``path`` is given, save the picture there.

    Parameters
    ----------
    world : World
    tableau : Tableau, optional
        A simulator run: steps with poses and truth; ``meta["trajectory"]`` if present.
    image_step : int, optional
        Draw this step's image as rays from its pose.
    path : str or Path, optional
        Output file; the format follows the suffix (.png, .svg, .pdf).

    Returns
    -------
    matplotlib.figure.Figure
    """
    x0, y0, x1, y1 = world.bounds()
    width, height = x1 - x0, y1 - y0
    scale = min(14.0 / width, 9.0 / height)
    fig = Figure(figsize=(max(4.0, width * scale + 1.0), max(3.0, height * scale + 1.2)), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    _draw_world(ax, world)
    if tableau is not None:
        _draw_run(ax, world, tableau, scale)
        if image_step is not None:
            _draw_image(ax, tableau, image_step)
    ax.set_aspect("equal")
    margin = 0.04 * max(width, height)
    ax.set_xlim(x0 - margin, x1 + margin)
    ax.set_ylim(y0 - margin, y1 + margin)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or _title(world, tableau), fontsize=10)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path)
    return fig


def _title(world: World, tableau: Tableau | None) -> str:
    if tableau is None:
        return world.name
    truths = {s.truth for s in tableau.steps if s.truth is not None}
    policy = tableau.meta.get("policy", "run")
    return f"{world.name}: {policy}, {len(tableau)} dstate images, {len(truths)} true dstates"


def _draw_world(ax, world: World) -> None:
    ax.add_patch(Polygon(world.boundary, closed=True, facecolor="#f7f5ef", edgecolor="black", lw=1.6, zorder=1))
    for wall in world.walls:
        ax.plot(wall[:, 0], wall[:, 1], color="black", lw=1.6, zorder=2)
    for p in world.places:
        xa, ya, xb, yb = p.rect
        ax.add_patch(Rectangle((xa, ya), xb - xa, yb - ya, fill=False, ls=":", lw=0.8, ec="#4a7ab8", zorder=2))
        ax.text(xa + 0.05 * (xb - xa), yb - 0.06 * (yb - ya), p.id, color="#4a7ab8", fontsize=7, va="top",
                zorder=3)
    for b in world.boxes:
        colour = CLUTTER_COLOURS.get(b.kind, "#999999")
        ax.add_patch(Polygon(b.corners(), closed=True, facecolor=colour, edgecolor="black", lw=0.5,
                             alpha=0.6 if b.jitter else 0.9, zorder=3))
    for d in world.discs:
        ax.add_patch(Circle(d.center, d.radius, facecolor=CLUTTER_COLOURS.get(d.kind, "#999999"),
                            edgecolor="black", lw=0.5, alpha=0.6 if d.jitter else 0.9, zorder=3))
    x, y, th = world.robot.start
    ax.add_patch(Circle((x, y), world.robot.radius, fill=False, ec="#2e8b57", ls="--", lw=0.8, zorder=4))


def _draw_run(ax, world: World, tableau: Tableau, scale: float) -> None:
    traj = tableau.meta.get("trajectory")
    if traj:
        t = np.asarray(traj)
        ax.plot(t[:, 0], t[:, 1], color="#d9534f", lw=0.5, alpha=0.45, zorder=4)
    groups: dict[str, list] = {}
    for s in tableau.steps:
        if s.pose is not None:
            groups.setdefault(str(s.truth), []).append(s.pose)
    x0, y0, x1, y1 = world.bounds()
    arrow = min(2.0, max(0.15, 0.035 * max(x1 - x0, y1 - y0)))  # metres, readable at any world size
    for n, (truth, poses) in enumerate(groups.items()):
        p = np.asarray(poses)
        x, y = p[:, 0].mean(), p[:, 1].mean()
        th = math.atan2(np.sin(p[:, 2]).mean(), np.cos(p[:, 2]).mean())
        ax.scatter(p[:, 0], p[:, 1], s=2, color="#1f3b73", alpha=0.3, zorder=5)
        ax.annotate("", xy=(x + arrow * math.cos(th), y + arrow * math.sin(th)), xytext=(x, y),
                    arrowprops=dict(arrowstyle="-|>", color="#1f3b73", lw=1.2), zorder=6)
        # Number beside the arrow's tail, on the side away from the heading, so numbers at one place
        # (one per heading) do not overlap.
        lx, ly = x - 0.9 * arrow * math.cos(th), y - 0.9 * arrow * math.sin(th)
        ax.text(lx, ly, f"{n}", fontsize=7, ha="center", va="center", color="#1f3b73", zorder=7,
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="#1f3b73", lw=0.5))
    ax.text(0.01, 0.01, "  ".join(f"{n}={t}" for n, t in enumerate(groups)), transform=ax.transAxes,
            fontsize=6, color="#1f3b73", va="bottom", wrap=True)


def _draw_image(ax, tableau: Tableau, index: int) -> None:
    step = tableau.steps[index]
    if step.image is None or step.pose is None:
        raise ValueError(f"step {index} has no image or no pose to draw")
    laser = tableau.meta.get("laser", {})
    n = len(step.image)
    a0 = laser.get("angle_min", -math.pi / 2)
    inc = laser.get("angle_increment", math.pi / (n - 1))
    rmax = laser.get("range_max", max(step.image))
    x, y, th = step.pose
    r = np.asarray(step.image)
    a = th + a0 + inc * np.arange(n)
    ex, ey = x + r * np.cos(a), y + r * np.sin(a)
    hit = r < rmax * 0.999
    segs = np.stack([np.column_stack([np.full(n, x), np.full(n, y)]), np.column_stack([ex, ey])], axis=1)
    from matplotlib.collections import LineCollection

    ax.add_collection(LineCollection(segs[hit], colors="#f0ad4e", lw=0.3, alpha=0.35, zorder=5))
    ax.add_collection(LineCollection(segs[~hit], colors="#cccccc", lw=0.3, alpha=0.5, zorder=5))
    ax.scatter(ex[hit], ey[hit], s=1.5, color="#c77700", zorder=6)
    ax.text(x, y, f" image of step {index}", fontsize=6, color="#c77700", zorder=7)
