"""Images as the learners take them: one place that reads laser scans (and their dstates) into arrays.

An image is a point in R^n (the paper's 180 ranges); the learners are not told it is a range scan.
Non-finite readings (``inf``: a beam that returned nothing) are read as drop-outs at the largest finite
range in the data; ``nan`` is an error. Tableaux never hold either (the format refuses them), so this
matters for images handed to the learners directly.
"""

from __future__ import annotations

import numpy as np


def as_images(images) -> np.ndarray:
    """Images as a float (n, d) array; ``inf`` read as a drop-out at the largest finite range.

    >>> as_images([[1.0, float("inf")], [3.0, 2.0]]).tolist()
    [[1.0, 3.0], [3.0, 2.0]]
    """
    X = np.asarray(images, dtype=float)
    if X.ndim != 2:
        raise ValueError(f"images must be a 2-D array (n_images, n_values), got shape {X.shape}")
    if np.isnan(X).any():
        raise ValueError("images contain nan")
    if np.isinf(X).any():
        finite = X[np.isfinite(X)]
        X = np.where(np.isinf(X), finite.max() if finite.size else 0.0, X)
    return X


def as_labels(dstates, n: int) -> np.ndarray:
    """The dstate of each of ``n`` images as an array, checked to be one per image.

    >>> as_labels(["S0", "S1"], 2).tolist()
    ['S0', 'S1']
    """
    y = np.asarray(dstates)
    if y.shape != (n,):
        raise ValueError(f"dstates must have shape ({n},), got {y.shape}")
    return y
