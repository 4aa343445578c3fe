"""Argument types of the ``bootmap`` command, shared by every sub-command (argparse ``type=`` callables):
each turns a bad value into a message naming what was expected, and argparse exits 2 with it."""

from __future__ import annotations

import argparse

#: Where a log's dstates are chosen (``--dstates``): at odometry's turns, or at the places the laser shows.
DSTATE_CHOICES = ("turns", "places")

#: The learners an experiment can draw beside nearest neighbour (``--learner``): the names of
#: :func:`bootmap.recognise.default_learners`, listed here so that the command line starts without scikit-learn.
LEARNERS = ("1-NN", "3-NN", "logistic", "linear SVM", "RBF SVM", "MLP (32)", "despiked LDA", "aligned LDA",
            "aligned mean", "aligned by folds")
DEFAULT_LEARNER = "aligned by folds"


def learner(text: str) -> str:
    """A learner's name, one of :data:`LEARNERS`."""
    if text not in LEARNERS:
        raise argparse.ArgumentTypeError(f"unknown learner {text!r}; known: {', '.join(LEARNERS)}")
    return text


def levels(text: str) -> list[str]:
    """'causal,topological' -> the level names (checked against the axiom directory when it is loaded)."""
    return [x.strip() for x in text.split(",") if x.strip()]


def quantum(text: str) -> float:
    """Degrees to round angles to: in (0, 180]."""
    try:
        q = float(text)
    except ValueError:
        q = float("nan")
    if not 0 < q <= 180:
        raise argparse.ArgumentTypeError(f"expected degrees in (0, 180], got {text!r}")
    return q


def seeds(text: str) -> list[int]:
    """'1,2,3' or '1-5' -> a list of seeds (non-negative, each once)."""
    hint = "expected seeds like 1,2,3 or 1-5 (non-negative integers)"
    parts = [x.strip() for x in text.split(",")]
    if any(not x for x in parts):
        raise argparse.ArgumentTypeError(f"{hint}, got {text!r}: an empty seed between commas")
    out: list[int] = []
    for part in parts:
        lo, _, hi = part.partition("-")
        if not lo.isdigit() or (hi and not hi.isdigit()):
            raise argparse.ArgumentTypeError(f"{hint}, got {text!r}")
        first, last = int(lo), int(hi) if hi else int(lo)
        if last < first:
            raise argparse.ArgumentTypeError(f"the range {part!r} runs backwards: write {last}-{first}")
        out += [x for x in range(first, last + 1) if x not in out]
    return out


def count(what: str, minimum: int = 1):
    """An argparse type: an integer of at least ``minimum``."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number ({what}), got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected {what} >= {minimum}, got {value}")
        return value
    return parse


def seconds(text: str) -> float:
    """A time limit: finite and not negative."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected seconds (a number >= 0), got {text!r}")
    return value


def positive(unit: str):
    """An argparse type: a finite number above 0, in ``unit`` (metres, degrees)."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not 0 < value < float("inf"):
            raise argparse.ArgumentTypeError(f"expected {unit} (a number > 0), got {text!r}")
        return value
    return parse


def setting(text: str) -> tuple[str, object]:
    """'laser.noise_sd=0.02' -> ('laser.noise_sd', 0.02): a world field and its value, read as TOML
    reads a value (numbers, true/false, quoted strings, arrays); a bare word is taken as a string."""
    key, eq, value = text.partition("=")
    key = key.strip()
    if not eq or not key or not value.strip():
        raise argparse.ArgumentTypeError(f"expected SECTION.FIELD=VALUE, e.g. laser.noise_sd=0.02, got {text!r}")
    import tomllib

    try:
        parsed = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        parsed = value.strip()
    return key, parsed


def add_calibrate(parser, prefix: str = "") -> None:
    """``--no-calibrate``: keep a log's odometry as recorded (bootmap.ingest.calibrate)."""
    parser.add_argument("--no-calibrate", action="store_true",
                        help=f"{prefix}keep the log's odometry as recorded, without calibrating its heading by the "
                             "laser where it drifts (bootmap.ingest.calibrate)")
