"""Place recognition by scan matching on the real logs, beside the raw-scan distance.

For every log: the tableau's visits (one laser image per dstate), all-pairs scores by
:class:`bootmap.scan_match.ScanMatcher` (defaults, never fitted to these logs) and by the raw-scan
descriptor (the negated mean absolute difference of the beams). For each visit k the best-scoring earlier
visit j < k is its guess; sweeping a threshold on that score, a guess is right when the corrected poses of k
and j lie within 3 m. Recall = right guesses / visits with some earlier visit within 3 m. Printed: recall at
95% and 99% precision, average precision, seconds for the log's all-pairs scores; and for consecutive
visits within 3 m of each other (a turn's two ends), the median error of the scan-match transform against the relative corrected pose.

Run: PYTHONPATH=py .venv/bin/python bench/scan_match_bench.py [--jobs 2] [LOG ...]
"""

from __future__ import annotations

import argparse
import glob
import math
import sys
import time

import numpy as np

from bootmap.ingest.ingest import log_tableau, read_log
from bootmap.scan_match import ScanMatcher

LOGS = sorted(glob.glob("/work/shared/logs/*.gz")) + ["killian"]
RADIUS_M = 3.0


def best_earlier(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For every visit k >= 1: the earlier visit j < k of highest score, and that score."""
    n = len(S)
    j = np.array([int(np.argmax(S[k, :k])) for k in range(1, n)], dtype=int)
    return j, S[np.arange(1, n), j]


def recognition(S: np.ndarray, poses: np.ndarray, radius_m: float = RADIUS_M) -> dict:
    """Recall at 95% and 99% precision and average precision of the best-earlier-visit guesses."""
    xy = poses[:, :2]
    D = np.linalg.norm(xy[:, None] - xy[None], axis=-1)
    n = len(S)
    revisits = sum(bool((D[k, :k] <= radius_m).any()) for k in range(1, n))
    j, score = best_earlier(S)
    right = D[np.arange(1, n), j] <= radius_m
    order = np.argsort(-score, kind="stable")
    tp = np.cumsum(right[order])
    precision = tp / np.arange(1, len(order) + 1)
    recall = tp / max(revisits, 1)
    # Only thresholds between distinct scores are real operating points.
    last = np.r_[score[order][1:] != score[order][:-1], True]
    precision, recall, hit = precision[last], recall[last], right[order]

    def at(p):
        ok = precision >= p
        return float(recall[ok].max()) if ok.any() else 0.0

    # Average precision: the mean, over right guesses, of precision at their rank (recall-normalised).
    ranks = np.flatnonzero(hit)
    ap = float(np.sum(tp[ranks] / (ranks + 1)) / max(revisits, 1))
    return {"revisits": revisits, "r95": at(0.95), "r99": at(0.99), "ap": ap}


def relative(pa, pb) -> tuple[float, float, float]:
    c, s = math.cos(pa[2]), math.sin(pa[2])
    dx, dy = pb[0] - pa[0], pb[1] - pa[1]
    return c * dx + s * dy, -s * dx + c * dy, (pb[2] - pa[2] + math.pi) % (2 * math.pi) - math.pi


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("logs", nargs="*", default=LOGS)
    p.add_argument("--jobs", type=int, default=2, help="processes for the all-pairs scores")
    args = p.parse_args(argv)
    matcher = ScanMatcher(n_jobs=args.jobs)
    print(f"{'log':<14}{'visits':>7}{'revisits':>9} | {'scan match: R@95':>17}{'R@99':>6}{'AP':>6}{'s':>6}"
          f" | {'raw: R@95':>10}{'R@99':>6}{'AP':>6} | consecutive within 3 m: {'pairs':>5}{'dxy m':>6}{'dth deg':>8}{'score':>6}")
    for log in args.logs:
        tab = log_tableau(read_log(log), source=log)
        images = np.array([s.image for s in tab.steps])
        poses = np.array([s.pose for s in tab.steps])
        start = time.perf_counter()
        S = matcher.scores(images)
        seconds = time.perf_counter() - start
        raw = -np.abs(images[:, None] - images[None]).mean(axis=-1)
        m, r = recognition(S, poses), recognition(raw, poses)
        errs = []
        for k in range(len(images) - 1):
            want = relative(poses[k], poses[k + 1])
            if math.hypot(want[0], want[1]) > RADIUS_M:
                continue  # a travel's two ends: different places, nothing to match
            got = matcher.match(images[k], images[k + 1])
            errs.append((math.dist(got.transform[:2], want[:2]),
                         abs(math.degrees((got.transform[2] - want[2] + math.pi) % (2 * math.pi) - math.pi)),
                         got.score))
        e = np.median(np.array(errs), axis=0) if errs else np.full(3, np.nan)
        name = log.rsplit("/", 1)[-1].removesuffix("-corrected.log.gz")
        print(f"{name:<14}{len(images):>7}{m['revisits']:>9} | {m['r95']:>17.0%}{m['r99']:>6.0%}{m['ap']:>6.2f}"
              f"{seconds:>6.1f} | {r['r95']:>10.0%}{r['r99']:>6.0%}{r['ap']:>6.2f} | "
              f"{'':13}{len(errs):>5}{e[0]:>6.2f}{e[1]:>8.1f}{e[2]:>6.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
