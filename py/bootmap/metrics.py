"""Scores of a map against the truth."""

from __future__ import annotations

from typing import Hashable, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment
from sklearn.metrics.cluster import contingency_matrix


def dstate_accuracy(truth: Sequence[Hashable], found: Sequence[Hashable]) -> float:
    """Fraction of time points whose found dstate is their true one, under the best one-to-one renaming.

    A map that merges two true dstates, or splits one, loses the smaller part: renaming is one-to-one.

    >>> dstate_accuracy(["a", "b", "a", "c"], ["S0", "S1", "S0", "S1"])
    0.75
    """
    if len(truth) != len(found):
        raise ValueError(f"{len(truth)} true labels but {len(found)} found ones")
    if not truth:
        return 1.0
    table = contingency_matrix([str(x) for x in truth], [str(x) for x in found])
    rows, cols = linear_sum_assignment(-table)
    return float(np.asarray(table)[rows, cols].sum() / len(truth))
