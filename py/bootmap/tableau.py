"""The tableau: a robot's experience as views (or images) at dstates and the actions between them.

This is the public, versioned exchange format of bootmap (``bootmap.tableau/1``), defined by the JSON
Schema in ``schemas/tableau-1.schema.json``. Loading validates against that schema and then checks what a
schema cannot say (every step but the last has an action, numbers are finite, images share one length).
Every problem is reported as a :class:`~bootmap.errors.TableauError` naming the step index and the field.

Example
-------
>>> t = Tableau.from_dict({"format": "bootmap.tableau/1", "steps": [
...     {"view": "V0", "action": {"type": "turn", "angle_deg": -90}}, {"view": "V1"}]})
>>> len(t), t.steps[0].action
(2, Turn(angle_deg=-90.0))
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field, replace
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any, ClassVar, Union

import jsonschema

from .errors import TableauError

FORMAT = "bootmap.tableau/1"


@dataclass(frozen=True, slots=True)
class Turn:
    """Turn in place. Negative angles turn right (clockwise), positive left; near +-180 turns around."""

    angle_deg: float
    #: The kind of action, as the tableau format and the action types name it.
    kind: ClassVar[str] = "turn"

    def to_dict(self) -> dict:
        return {"type": self.kind, "angle_deg": self.angle_deg}


@dataclass(frozen=True, slots=True)
class Travel:
    """Travel along a path to the next dstate, with the net heading change of a curved path."""

    distance_m: float
    heading_change_deg: float = 0.0
    #: The kind of action, as the tableau format and the action types name it.
    kind: ClassVar[str] = "travel"

    def to_dict(self) -> dict:
        d = {"type": self.kind, "distance_m": self.distance_m}
        if self.heading_change_deg:
            d["heading_change_deg"] = self.heading_change_deg
        return d


Action = Union[Turn, Travel]


@dataclass(frozen=True, slots=True)
class Step:
    """One time point: the view (or image) at a dstate, and the action to the next time point."""

    view: str | None = None
    action: Action | None = None
    image: tuple[float, ...] | None = None
    truth: str | int | None = None
    pose: tuple[float, float, float] | None = None
    #: The robot's own dead-reckoned pose here (x, y metres, theta radians, in its odometry frame): evidence
    #: the learning may use, where ``pose`` is the truth it never sees.
    odometry: tuple[float, float, float] | None = None

    def to_dict(self) -> dict:
        d: dict[str, Any] = {}
        if self.view is not None:
            d["view"] = self.view
        if self.action is not None:
            d["action"] = self.action.to_dict()
        if self.image is not None:
            d["image"] = list(self.image)
        if self.truth is not None:
            d["truth"] = self.truth
        if self.pose is not None:
            d["pose"] = list(self.pose)
        if self.odometry is not None:
            d["odometry"] = list(self.odometry)
        return d


def _beyond(match: Any, n: int) -> bool:
    """Whether a place match (``meta.place_matches``) names a time point at or after ``n``."""
    return isinstance(match, dict) and any(isinstance(match.get(k), int) and match[k] >= n for k in ("a", "b"))


@dataclass(frozen=True)
class Tableau:
    """A validated tableau. Build one with :meth:`from_dict`, :meth:`loads` or :func:`load`."""

    steps: tuple[Step, ...]
    world: str | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        # What from_dict checks of a document, checked of a tableau built in code too.
        for i, step in enumerate(self.steps):
            problem = _action_problem(step.action is not None, i == len(self.steps) - 1)
            if problem:
                raise TableauError(problem, f"tableau: steps[{i}].action")

    def __len__(self) -> int:
        return len(self.steps)

    @property
    def views(self) -> list[str | None]:
        return [s.view for s in self.steps]

    @property
    def actions(self) -> list[Action]:
        return [s.action for s in self.steps[:-1]]  # type: ignore[misc]

    def require_views(self, source: str = "tableau") -> None:
        """Raise unless every step has a view label (the resolver works on views, not raw images)."""
        for i, s in enumerate(self.steps):
            if s.view is None:
                raise TableauError("has no view: give every step a view label, or every step an image "
                                   "(then bootmap map clusters the images into views)", f"{source}: steps[{i}].view")

    def with_views(self, views: list[str]) -> "Tableau":
        """A copy with the given view labels (one per step), e.g. after clustering images."""
        if len(views) != len(self.steps):
            raise TableauError(f"got {len(views)} views for {len(self.steps)} steps")
        steps = tuple(replace(s, view=v) for v, s in zip(views, self.steps))
        return Tableau(steps, self.world, dict(self.meta))

    def prefix(self, n: int) -> "Tableau":
        """The first ``n`` time points: the experience as it was after ``n - 1`` actions."""
        if not 1 <= n <= len(self.steps):
            raise TableauError(f"a prefix of 1 to {len(self.steps)} time points, not {n}")
        last = self.steps[n - 1]
        steps = self.steps[:n - 1] + (replace(last, action=None),)
        meta = dict(self.meta)
        if isinstance(meta.get("place_matches"), list):  # what the laser says of pairs, within the prefix
            meta["place_matches"] = [m for m in meta["place_matches"] if not _beyond(m, n)]
        return Tableau(steps, self.world, meta)

    def place_matches(self) -> dict[tuple[int, int], float]:
        """The place matches the tableau carries (``meta.place_matches``), as ``{(earlier, later): score}``
        (the best score where a pair is given twice); empty where it carries none.

        Raises
        ------
        TableauError
            A match names a time point the tableau does not have, or one time point twice, or is not of that
            shape (where its meta was set in code, not read).
        """
        found = self.meta.get("place_matches")
        if found is None:
            return {}
        _check_place_matches(found, len(self.steps), "tableau")
        out: dict[tuple[int, int], float] = {}
        for match in found:
            pair = (min(match["a"], match["b"]), max(match["a"], match["b"]))
            out[pair] = max(out.get(pair, 0.0), float(match["score"]))
        return out

    @property
    def labelled(self) -> bool:
        """Every step has a view label (else the views are found by clustering the images)."""
        return all(s.view is not None for s in self.steps)

    def extend(self, more: Any, source: str = "request") -> "Tableau":
        """This tableau with more experience after it, from a document ``{"action": ..., "steps": [...]}``:
        ``action`` leads from this tableau's last step to the first new one.

        The new steps are checked as a document of their own, so errors name its fields
        (``request: steps[0].image``, ``request: action``), then against this tableau: view labels if it
        has them, else images only, of the length of its images.
        """
        if not isinstance(more, dict) or not {"action", "steps"} <= set(more):
            raise TableauError('expected an object with "action" and "steps"', source)
        new = Tableau.from_dict({"format": FORMAT, "steps": more["steps"]}, source)
        _check_schema(more["action"], source, _action_validator(), ("action",))
        link = _action(more["action"], f"{source}: action")
        labelled = self.labelled
        for i, step in enumerate(new.steps):
            if labelled and step.view is None:
                raise TableauError("missing: the stored tableau has view labels, so new steps need them",
                                   f"{source}: steps[{i}].view")
            if not labelled and (step.view is not None or step.image is None):
                raise TableauError("the stored tableau has images only (its views are found by clustering): "
                                   "give new steps an image and no view", f"{source}: steps[{i}]")
        length = next((len(s.image) for s in self.steps if s.image is not None), None)
        for i, step in enumerate(new.steps):
            if length is not None and step.image is not None and len(step.image) != length:
                raise TableauError(f"has {len(step.image)} values where the stored steps have {length}",
                                   f"{source}: steps[{i}].image")
        last = self.steps[-1]
        joined = replace(last, action=link)
        return Tableau(self.steps[:-1] + (joined,) + new.steps, self.world, dict(self.meta))

    def to_dict(self) -> dict:
        d: dict[str, Any] = {"format": FORMAT}
        if self.world is not None:
            d["world"] = self.world
        if self.meta:
            d["meta"] = self.meta
        d["steps"] = [s.to_dict() for s in self.steps]
        return d

    def dumps(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def loads(cls, text: str | bytes, source: str = "tableau") -> "Tableau":
        """Parse JSON text (bytes must be UTF-8, as JSON is). NaN and Infinity, which Python's json accepts
        but JSON forbids, are rejected."""
        if isinstance(text, bytes):
            text = _utf8(text, source)
        try:
            data = json.loads(text, parse_constant=_reject_constant)
        except _NonFinite as e:
            raise TableauError(f"{e.args[0]} is not a finite number (JSON allows none)", source) from None
        except json.JSONDecodeError as e:
            raise TableauError(f"not valid JSON: {e.msg} at line {e.lineno} column {e.colno}", source) from None
        except RecursionError:
            raise TableauError("JSON nested too deeply", source) from None
        return cls.from_dict(data, source)

    @classmethod
    def from_dict(cls, data: Any, source: str = "tableau") -> "Tableau":
        """Validate a parsed JSON document and build the tableau."""
        _check_schema(data, source)
        raw = data["steps"]
        steps = tuple(_step(s, i, i == len(raw) - 1, source) for i, s in enumerate(raw))
        _check_images(steps, source)
        meta = dict(data.get("meta", {}))
        _check_place_matches(meta.get("place_matches", []), len(steps), source)
        return cls(steps, data.get("world"), meta)


#: Files a robot's log comes in, which ``bootmap ingest`` reads into a tableau.
LOG_SUFFIXES = (".bag", ".db3", ".mcap", ".g2o", ".log", ".gz", ".zip", ".clf", ".carmen")


#: The name that stands for standard input where a tableau file is named (``bootmap simulate W | bootmap map -``).
STDIN = "-"


def load(path: str | Path) -> Tableau:
    """Read and validate a tableau file (``-``: standard input); errors name the file (and, for a robot's
    log, the command that reads one)."""
    if str(path) == STDIN:
        return Tableau.loads(sys.stdin.buffer.read(), "stdin")
    path = Path(path)
    try:
        text = path.read_bytes()
    except OSError as e:
        raise TableauError(f"cannot read: {e.strerror}", str(path)) from None
    try:
        return Tableau.loads(text, str(path))
    except TableauError as e:
        if path.suffix.lower() in LOG_SUFFIXES or path.is_dir():
            raise TableauError(f"{e.reason}; a robot's log is read into a tableau by `bootmap ingest "
                               f"{path.name} -o run.json`", str(path)) from None
        raise


def _utf8(data: bytes, source: str) -> str:
    """The text of JSON bytes, or an error naming where they stop being UTF-8."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        column = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise TableauError(f"not UTF-8 text (JSON is): byte 0x{data[e.start]:02x} at line {line} column {column}"
                           " (a binary file, or text saved in another encoding such as Latin-1)", source) from None


@lru_cache(maxsize=1)
def schema() -> dict:
    """The JSON Schema of the tableau format (also served by the HTTP service)."""
    text = resources.files("bootmap").joinpath("schemas/tableau-1.schema.json").read_text()
    return json.loads(text)


class _NonFinite(Exception):
    pass


def _reject_constant(name: str):
    raise _NonFinite(name)


def _pointer(path) -> str:
    """steps/3/action/angle_deg -> steps[3].action.angle_deg"""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


@lru_cache(maxsize=1)
def _validator() -> jsonschema.protocols.Validator:
    return jsonschema.Draft202012Validator(schema())


@lru_cache(maxsize=1)
def _action_validator() -> jsonschema.protocols.Validator:
    """The schema of one action (``$defs/action``), for the action an extension starts with."""
    return jsonschema.Draft202012Validator({"$defs": schema()["$defs"], "$ref": "#/$defs/action"})


@lru_cache(maxsize=1)
def _fast_validator():
    """jsonschema-rs's compiled validator of the same schema: a 401-step tableau is checked in about
    1 ms instead of 50 ms. Only its yes or no is used; jsonschema names the error of an invalid one."""
    try:
        import jsonschema_rs
    except ImportError:  # optional at run time: without it every check goes the slow way
        return None
    return jsonschema_rs.validator_for(schema())


def _check_schema(data: Any, source: str, validator: jsonschema.protocols.Validator | None = None,
                  prefix: tuple = ()) -> None:
    """Raise TableauError for the error a person has to fix first; ``prefix`` is the path of ``data``
    in the document."""
    fast = _fast_validator() if validator is None else None
    if fast is not None and fast.is_valid(data):
        return
    errors = list((validator or _validator()).iter_errors(data))
    if not errors:
        return
    # The deepest error is the one that names the field a person has to fix.
    err = max(errors, key=lambda e: (len(e.absolute_path), -len(e.context)))
    path = list(prefix) + list(err.absolute_path)
    if err.validator == "anyOf" and err.absolute_path and path[-1] != "action":
        msg = "a step needs a view or an image"
    elif err.validator == "additionalProperties":
        msg = err.message.replace("Additional properties are not allowed", "unknown field")
    elif err.validator == "enum" and path[-2:-1] == ["action"]:
        msg = f"unknown action type {err.instance!r} (expected 'turn' or 'travel')"
    elif err.validator == "const" and path == ["format"]:
        msg = f"unsupported format {err.instance!r} (expected {FORMAT!r})"
    elif err.validator == "pattern" and path[-1:] == ["view"]:
        msg = "a view label cannot contain the NUL character (clingo would cut the label there)"
    elif err.validator == "minItems" and path == ["steps"]:
        msg = "a tableau needs at least one step"
    else:
        msg = err.message
    raise TableauError(msg, f"{source}: {_pointer(path)}")


def _finite(x: float, where: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise TableauError(f"{x!r} is not a number", where)
    try:
        value = float(x)
    except OverflowError:  # an integer literal beyond any float
        raise TableauError(f"a number of {len(str(abs(x)))} digits is too large", where) from None
    if not math.isfinite(value):
        raise TableauError(f"{x!r} is not a finite number", where)
    return value


def _action_problem(has_action: bool, last: bool) -> str | None:
    """What is wrong with a step's action, if anything: an action leads from each step to the next, so
    every step has one but the last (``steps[i].action`` is step i -> i + 1)."""
    if not has_action and not last:
        return "missing: every step but the last needs an action to the next step"
    if has_action and last:
        return "the last step has an action but no step follows it"
    return None


def _step(d: dict, i: int, last: bool, source: str) -> Step:
    where = f"{source}: steps[{i}]"
    a = d.get("action")
    problem = _action_problem(a is not None, last)
    if problem:
        raise TableauError(problem, where + ".action")
    action = None if a is None else _action(a, where + ".action")
    image = None
    if "image" in d:
        image = tuple(_finite(x, f"{where}.image[{j}]") for j, x in enumerate(d["image"]))
    return Step(d.get("view"), action, image, d.get("truth"), _pose(d, "pose", where),  # type: ignore[arg-type]
                _pose(d, "odometry", where))


def _pose(d: dict, key: str, where: str) -> tuple[float, ...] | None:
    """A step's ``pose`` or ``odometry`` (x, y, theta), each number finite, or None where it has none."""
    if key not in d:
        return None
    return tuple(_finite(x, f"{where}.{key}[{j}]") for j, x in enumerate(d[key]))


def _action(a: dict, where: str) -> Action:
    """An action from its (schema-checked) document."""
    if a["type"] == "turn":
        return Turn(_finite(a["angle_deg"], where + ".angle_deg"))
    return Travel(_finite(a["distance_m"], where + ".distance_m"),
                  _finite(a.get("heading_change_deg", 0.0), where + ".heading_change_deg"))


def _check_place_matches(matches: Any, n: int, source: str) -> None:
    """Each place match (``meta.place_matches``) is ``{a, b, score}`` naming two time points of the tableau's
    ``n``, not one twice, with a score from 0 to 1. A tableau read is checked for the shape by the schema as
    well; one built in code only here."""
    where = f"{source}: meta.place_matches"
    if not isinstance(matches, list):
        raise TableauError("must be a list of {a, b, score}", where)
    for k, match in enumerate(matches):
        if not isinstance(match, dict):
            raise TableauError("must be an object {a, b, score}", f"{where}[{k}]")
        for key in ("a", "b"):
            t = match.get(key)
            if not isinstance(t, int) or isinstance(t, bool) or not 0 <= t < n:
                raise TableauError(f"names no time point of the tableau ({t!r}; it has 0 to {n - 1})",
                                   f"{where}[{k}].{key}")
        score = match.get("score")
        if not isinstance(score, (int, float)) or isinstance(score, bool) or not 0 <= score <= 1:
            raise TableauError(f"must be a number from 0 to 1, not {score!r}", f"{where}[{k}].score")
        if match["a"] == match["b"]:
            raise TableauError(f"matches time point {match['a']} with itself", f"{where}[{k}]")


def _check_images(steps: tuple[Step, ...], source: str) -> None:
    lengths = {len(s.image) for s in steps if s.image is not None}
    if len(lengths) > 1:
        first = next(len(s.image) for s in steps if s.image is not None)
        for i, s in enumerate(steps):
            if s.image is not None and len(s.image) != first:
                raise TableauError(f"has {len(s.image)} values where steps before have {first}",
                                   f"{source}: steps[{i}].image")
