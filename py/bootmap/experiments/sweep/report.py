"""A sweep's summary (``summary.md``) and figures, from its results table.

Cells are grouped by everything but the seed (world, noise, clusterer, learner, levels, quantum): each
group is a row of the summary, with the share of seeds whose map is exactly the truth, k chosen by M and
the learners' accuracy at 90 images (mean, standard deviation, range), the share on which every check of
the paper holds, and seconds per cell. Failed and timed-out cells are listed with their errors.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

GROUP = ("world", "noise", "clusterer", "learner", "levels", "quantum")
FIGURES = ("accuracy_vs_noise.png", "k_chosen.png", "map_exact.png", "learner_curves.png")


def groups(table: list[dict]) -> dict[tuple, list[dict]]:
    """Rows by group (every axis but the seed), in the table's order."""
    out: dict[tuple, list[dict]] = {}
    for row in table:
        out.setdefault(tuple(row[k] for k in GROUP), []).append(row)
    return out


def summary_text(name: str, table: list[dict], how: str) -> str:
    """The Markdown summary; ``how`` says where and how long it ran."""
    axes = [k for k in GROUP if len({r[k] for r in table}) > 1 or k in ("world", "noise")]
    lines = [f"# Sweep {name}", "", how, "",
             "| " + " | ".join(axes) + " | seeds | failed | map exact | k by M: mean +- sd (range) | "
             "NN at 90: mean +- sd (range) | learner at 90 | all checks | s/cell |",
             "|" + "---|" * (len(axes) + 8)]
    for key, rows in groups(table).items():
        ok = [r for r in rows if r["status"] == "ok"]
        failed = len(rows) - len(ok)
        learner = key[GROUP.index("learner")]
        lines.append("| " + " | ".join(str(dict(zip(GROUP, key))[a]) for a in axes) + " | " + " | ".join([
            str(len(rows)), str(failed), _share(rows, "map_exact"), _spread([r["k"] for r in ok], "{:.3g}"),
            _spread([r["nn_at_90"] for r in ok], "{:.1%}"),
            "-" if learner == "1-NN" else f"{learner}: {_spread([r['learner_at_90'] for r in ok], '{:.1%}')}",
            _share(rows, "all_checks"), _mean([r["seconds"] for r in rows], "{:.2f}")]) + " |")
    bad = [r for r in table if r["status"] != "ok" or r.get("error")]
    if bad:
        lines += ["", "## Cells that failed, timed out or found no map", ""]
        lines += [f"- `{r['cell_id']}`: {r['status']}: {str(r['error']).splitlines()[0]}" for r in bad]
    lines += ["", "map exact: the true topology, proved minimal, every image on its dstate; NN at 90: nearest "
              "neighbour, 10-fold CV, images labelled by the map; failed cells count as not exact.", ""]
    lines += [f"![{f[:-4].replace('_', ' ')}]({f})" for f in FIGURES]
    return "\n".join(lines) + "\n"


def _share(rows: list[dict], key: str) -> str:
    return f"{sum(bool(r[key]) for r in rows) / len(rows):.0%}"


def _spread(values: list, fmt: str) -> str:
    known = [float(v) for v in values if v is not None]
    if not known:
        return "-"
    f = fmt.format
    return f"{f(np.mean(known))} +- {f(np.std(known))} ({f(min(known))}-{f(max(known))})"


def _mean(values: list, fmt: str) -> str:
    known = [float(v) for v in values if v is not None]
    return fmt.format(np.mean(known)) if known else "-"


# ---------------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------------

def write_figures(table: list[dict], out: Path) -> None:
    """accuracy against noise, k chosen, map exactness per world, learner curves (``FIGURES``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    noises = list(dict.fromkeys(r["noise"] for r in table))
    worlds = list(dict.fromkeys(r["world"] for r in table))
    ok = [r for r in table if r["status"] == "ok"]
    for name, draw in (("accuracy_vs_noise.png", _accuracy_vs_noise), ("k_chosen.png", _k_chosen),
                       ("map_exact.png", _map_exact), ("learner_curves.png", _learner_curves)):
        fig, ax = plt.subplots(figsize=(7, 4.2))
        draw(ax, table, ok, worlds, noises)
        fig.tight_layout()
        fig.savefig(out / name, dpi=100)
        plt.close(fig)


def _accuracy(row: dict) -> float | None:
    """The cell's learner's accuracy at 90 images (nearest neighbour's when the learner is 1-NN)."""
    return row["nn_at_90"] if row["learner"] == "1-NN" else row["learner_at_90"]


def _accuracy_vs_noise(ax, table, ok, worlds, noises) -> None:
    for world in worlds:
        for learner in dict.fromkeys(r["learner"] for r in ok if r["world"] == world):
            means, sds = [], []
            for n in noises:
                acc = [_accuracy(r) for r in ok if (r["world"], r["learner"], r["noise"]) == (world, learner, n)]
                acc = [a for a in acc if a is not None]
                means.append(np.mean(acc) if acc else np.nan)
                sds.append(np.std(acc) if acc else np.nan)
            ax.errorbar(range(len(noises)), means, yerr=sds, fmt="o-", capsize=3, label=f"{world}, {learner}")
    ax.axhline(0.85, color="grey", lw=0.8, ls="--")
    ax.set_xticks(range(len(noises)), noises, rotation=15)
    ax.set_ylabel("accuracy at 90 images (10-fold CV)")
    ax.set_xlabel("noise level")
    ax.set_title("recognition against noise (mean +- sd over seeds)")
    ax.legend(fontsize=8)


def _k_chosen(ax, table, ok, worlds, noises) -> None:
    series = [(w, n) for w in worlds for n in noises]
    ks = sorted({r["k"] for r in ok}) or [0]
    width = 0.8 / max(1, len(series))
    for i, (w, n) in enumerate(series):
        counts = Counter(r["k"] for r in ok if (r["world"], r["noise"]) == (w, n))
        ax.bar(np.arange(len(ks)) + i * width, [counts.get(k, 0) for k in ks], width, label=f"{w}, {n}")
    ax.set_xticks(np.arange(len(ks)) + 0.4 - width / 2, [str(k) for k in ks])
    ax.set_xlabel("k chosen by M")
    ax.set_ylabel("cells")
    ax.set_title("views: k chosen by M")
    ax.legend(fontsize=8)


def _map_exact(ax, table, ok, worlds, noises) -> None:
    width = 0.8 / max(1, len(noises))
    for i, n in enumerate(noises):
        share = []
        for w in worlds:
            rows = [r for r in table if (r["world"], r["noise"]) == (w, n)]
            share.append(sum(bool(r["map_exact"]) for r in rows) / len(rows) if rows else 0)
        ax.bar(np.arange(len(worlds)) + i * width, share, width, label=n)
    ax.set_xticks(np.arange(len(worlds)) + 0.4 - width / 2, worlds)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("share of cells with the exact map")
    ax.set_title("map exactness per world")
    ax.legend(fontsize=8, title="noise")


def _learner_curves(ax, table, ok, worlds, noises) -> None:
    for (world, learner, noise), rows in _by(ok, ("world", "learner", "noise")).items():
        curves = [r["curve"] for r in rows if r.get("curve")]
        if not curves:
            continue
        # The learner's curve is drawn at fewer sizes than nearest neighbour's (rows stored before that
        # hold one list of sizes for both).
        at = "sizes" if learner == "1-NN" else "learner_sizes"
        sizes = curves[0].get(at, curves[0]["sizes"])
        ys = np.array([c["nn" if learner == "1-NN" else "learner"] for c in curves
                       if c.get(at, c["sizes"]) == sizes])
        label = f"{world}, {learner}" + (f", {noise}" if len(noises) > 1 else "")
        ax.errorbar(sizes, ys.mean(axis=0), yerr=ys.std(axis=0), fmt="o-", capsize=2, label=label)
    ax.set_xlabel("images (training set size)")
    ax.set_ylabel("accuracy (10-fold CV)")
    ax.set_ylim(0, 1.02)
    ax.set_title("learning curves (mean +- sd over seeds)")
    ax.legend(fontsize=7)


def _by(rows: list[dict], keys: tuple[str, ...]) -> dict[tuple, list[dict]]:
    out: dict[tuple, list[dict]] = {}
    for r in rows:
        out.setdefault(tuple(r[k] for k in keys), []).append(r)
    return out
