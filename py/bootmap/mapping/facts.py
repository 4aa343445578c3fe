"""Tableau -> clingo facts, as data.

Labels and numbers reach clingo as symbols built with clingo's API (through :mod:`.vocabulary`) and are
added through the backend, so a view label such as ``a). #script (python)`` is just a string: no user
text ever becomes program text. Each action's angle is the angle of its learned type (:mod:`.motion`), or
the measurement rounded to a quantum when one is given, so that sensor noise on turns does not make the
same action look like many actions, nor accumulate in headings.

Facts (see docs/asp.md): ``view(T, "label")``, ``turn(T, A)``, ``travel(T, C)``, with
``A``, ``C`` integer degrees in (-180, 180]; ``turn(T, 180)`` is a turn-around.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Iterable, Sequence

import clingo
import numpy as np
from clingo import Function, Number, String, Symbol

from ..tableau import Action, Tableau, Travel, Turn
from .compass import WallCompass
from .sectors import sector_angles
from .motion import (ActionType, LengthType, LengthTypes, MotionPrimitives, TypeSuspect, action_types, measured_angle,
                     quantise, resolution_of, turns_exact, type_suspects)
from .vocabulary import LENGTH, PASSES_THROUGH, RESUME, TRAVEL, TURN, VIEW, action_term


def read_actions(tableau: Tableau, quantum_deg: float | None = None) -> tuple[list[int], list[ActionType]]:
    """The angle the axioms see for each action of the tableau (a turn's angle, a travel's net heading
    change), and the action types: learned (:mod:`.motion`), or, given a quantum, the measurements
    rounded to it."""
    typing = typing_of(tableau, quantum_deg)
    return typing.angles, typing.types


def typed_actions(tableau: Tableau, quantum_deg: float | None = None) -> tuple[list[int], list[ActionType], int | None]:
    """:func:`read_actions`, and the grid the learned types lie on (None with a fixed quantum, or no
    actions): the grid says which readings may be mistyped (:func:`.motion.type_suspects`)."""
    typing = typing_of(tableau, quantum_deg)
    return typing.angles, typing.types, typing.grid


@dataclass(frozen=True)
class Typing:
    """How a tableau's actions are read and typed.

    Attributes
    ----------
    angles : list of int
        The angle the axioms see for each action (its type's).
    types : list of ActionType
        The action types.
    grid : int or None
        The grid the learned types lie on (None with a fixed quantum, or no actions).
    read : list of Action
        The actions as read: the walls' reading of each angle where the laser confirmed one
        (:mod:`.compass`), else odometry's.
    alternatives : dict
        Time point -> the other angle (on the grid) an action may have, where the walls leave odometry
        two candidates it cannot tell apart.
    """

    angles: list[int]
    types: list[ActionType]
    grid: int | None
    read: list[Action]
    alternatives: dict[int, int] = field(default_factory=dict)

    def suspects(self, angles: Sequence[int] | None = None) -> list[TypeSuspect]:
        """The actions that may be mistyped (the resolver weighs each, :mod:`.search.retyping`): readings
        far from their type (:func:`.motion.type_suspects`), and actions the walls leave ambiguous."""
        angles = list(self.angles if angles is None else angles)
        if self.grid is None:
            return []
        found = {s.t: s for s in type_suspects(self.read, angles, self.grid)}
        for t, alt in self.alternatives.items():
            if t not in found and alt != angles[t]:
                a = self.read[t]
                found[t] = TypeSuspect(t, a.kind, measured_angle(a),
                                       angles[t], alt)
        return [found[t] for t in sorted(found)]


def odometry_axis(meta: dict | None) -> float | None:
    """The building's main axis (radians) that ingest read from the whole odometry track of a log
    (``meta.odometry.axis_deg``), or None where the tableau does not say (its dstates' poses then give it).

    >>> round(odometry_axis({"odometry": {"axis_deg": 45.0}}), 4), odometry_axis({})
    (0.7854, None)
    """
    axis = ((meta or {}).get("odometry") or {}).get("axis_deg")
    return None if axis is None else float(np.radians(axis))


def typing_of(tableau: Tableau, quantum_deg: float | None = None, compass: bool = True) -> Typing:
    """How the tableau's actions are read (:class:`Typing`): with a quantum, odometry's readings rounded to
    it; for a log that drove through its dstates with odometry at each, the changes of the building's
    sector the robot faced (:mod:`.sectors`); else the walls' readings where the tableau has laser images
    (:class:`.compass.WallCompass`), and types learned from them (:class:`.motion.MotionPrimitives`)."""
    actions = list(tableau.actions)
    resolution = resolution_of(tableau.meta, "angle_deg")
    if quantum_deg is not None:
        angles = [quantise(measured_angle(a), quantum_deg) for a in actions]
        return Typing(angles, action_types(actions, angles, resolution), None, actions)
    if not actions:
        return Typing([], [], None, [])
    if passes_through(tableau) and all(step.odometry is not None for step in tableau.steps):
        # a log: each dstate faces the building's sector its heading lies in (.sectors), the heading where
        # odometry began plus the actions' measured angles, along the odometry's path
        start = tableau.steps[0].odometry
        heading = start[2] + np.radians(np.concatenate([[0.0], np.cumsum([measured_angle(a) for a in actions])]))
        poses = [(step.odometry[0], step.odometry[1], h) for step, h in zip(tableau.steps, heading)]
        angles = sector_angles(poses, odometry_axis(tableau.meta))[:len(actions)]
        return Typing(angles, action_types(actions, angles, resolution), None, actions)
    walls = WallCompass().fit(tableau) if compass else None
    if walls is None or not walls.used_:
        learned = MotionPrimitives(resolution_deg=resolution).fit(actions)
        return Typing(learned.angles_, learned.types_, learned.grid_deg_, actions)
    read = walls.actions(actions)
    learned = MotionPrimitives(resolution_deg=0.0, exact_deg=0.0).fit(read, trusted=walls.confirmed_)
    grid = learned.grid_deg_
    alternatives = {t: quantise(a, grid) for t, a in enumerate(walls.alternatives_) if a is not None}
    return Typing(learned.angles_, with_walls(learned.types_, read, learned.angles_, walls.confirmed_), grid, read,
                  alternatives)


def with_walls(types: list[ActionType], actions: Sequence[Action], angles: Sequence[int], confirmed: Sequence[bool]
               ) -> list[ActionType]:
    """The action types, each saying how many of its actions' angles the walls read."""
    count: dict[tuple[str, int], int] = {}
    for a, angle, sure in zip(actions, angles, confirmed):
        key = (a.kind, angle)
        count[key] = count.get(key, 0) + bool(sure)
    return [replace(t, from_walls=count.get((t.kind, t.angle), 0)) for t in types]


def action_symbol(action: Action | None, angle: int, length: int | None = None) -> Symbol | None:
    """The action as the causal level names it (``turn(-90)``, ``travel``; ``travel(79)`` with the travel's
    length type where the tableau passes through dstates), or None after the last step."""
    if action is None:
        return None
    return action_term(action.kind, angle, length)


def passes_through(tableau: Tableau) -> bool:
    """Whether the robot drove through dstates without stopping at them (a log, whose dstates are chosen
    afterwards: ``meta["passes_through"]``), so that a travel may end at any dstate further on."""
    return bool(tableau.meta.get("passes_through", False))


def action_symbols(tableau: Tableau, angles: Sequence[int]) -> list[Symbol | None]:
    """Every step's action as the causal level names it (:func:`action_symbol`), None after the last."""
    lengths = travel_lengths(tableau) if passes_through(tableau) else {}
    return [action_symbol(s.action, a, lengths.get(t)) for t, (s, a) in enumerate(zip(tableau.steps, angles))]


def tableau_facts(tableau: Tableau, quantum_deg: float | None = None,
                  angles: Sequence[int] | None = None, lengths: dict[int, int] | None = None) -> list[Symbol]:
    """The tableau as ground facts (symbols). Requires every step to have a view label. ``angles`` are
    the actions' angles when already known (:func:`read_actions`), ``lengths`` the travels' length types
    (:func:`travel_lengths`)."""
    tableau.require_views()
    if angles is None:
        angles, _ = read_actions(tableau, quantum_deg)
    # Views and angles repeat: build each symbol once (every constructor is a call into clingo).
    strings: dict[str, Symbol] = {}
    numbers: dict[int, Symbol] = {}
    out: list[Symbol] = []
    # The vocabulary's names, with clingo's constructors called directly: this loop runs per step.
    view_name, turn_name, travel_name, length_name = VIEW.name, TURN.name, TRAVEL.name, LENGTH.name
    lengths = travel_lengths(tableau) if lengths is None else lengths
    for t, step in enumerate(tableau.steps):
        time = Number(t)
        view = strings.get(step.view) or strings.setdefault(step.view, String(step.view))  # type: ignore[arg-type]
        out.append(Function(view_name, [time, view]))
        if step.action is not None:
            name = turn_name if isinstance(step.action, Turn) else travel_name
            angle = angles[t]
            out.append(Function(name, [time, numbers.get(angle) or numbers.setdefault(angle, Number(angle))]))
            if t in lengths:
                out.append(Function(length_name, [time, Number(lengths[t])]))
    if passes_through(tableau):
        out.append(PASSES_THROUGH())
    return out


def travel_lengths(tableau: Tableau) -> dict[int, int]:
    """The length type (decimetres) of each travel, by its time point (:func:`travel_length_types`)."""
    return travel_length_types(tableau)[0]


def length_types_of(tableau: Tableau) -> list[LengthType]:
    """The tableau's travel lengths as types (what the map reports beside its action types)."""
    return travel_length_types(tableau)[1]


def travel_length_types(tableau: Tableau) -> tuple[dict[int, int], list[LengthType]]:
    """The length type (decimetres) of each travel by its time point, and the types, learned once
    (:class:`.motion.LengthTypes`, at the resolution the tableau states, or the distances show; noisy
    where the same odometry read its turns with noise)."""
    travels = [t for t, s in enumerate(tableau.steps) if isinstance(s.action, Travel)]
    distances = [tableau.steps[t].action.distance_m for t in travels]  # type: ignore[union-attr]
    noisy = not turns_exact(tableau.actions, resolution_of(tableau.meta, "angle_deg"))
    learned = LengthTypes(resolution_of(tableau.meta, "distance_m"), noisy=noisy).fit(distances)
    return dict(zip(travels, learned.labels_)), learned.types_


def add_facts(ctl: clingo.Control, facts: Iterable[Symbol]) -> None:
    """Add ground facts through the backend (before grounding, so the grounder sees them as facts)."""
    with ctl.backend() as backend:
        for sym in facts:
            backend.add_rule([backend.add_atom(sym)])


class Excerpts:
    """A tableau's facts (:func:`tableau_facts`), each read once for its time point, to cut excerpts from
    (reading a symbol's arguments is a call into clingo, and an explanation cuts dozens of excerpts).

    An excerpt is how an explanation states its evidence: these steps alone force the conclusion. It
    holds the facts of the kept time points only: their views, the actions between two kept time points,
    and ``resume(T)`` where a run of kept time points starts after a gap (the metrical level starts a frame
    of headings there: the turns in the gap are not part of the excerpt).
    """

    def __init__(self, facts: Sequence[Symbol]):
        self._whole = [sym for sym in facts if not sym.arguments]  # of the whole tableau (passes_through)
        self._timed = [(sym.arguments[0].number, VIEW.matches(sym), sym) for sym in facts if sym.arguments]

    def __call__(self, keep: Iterable[int]) -> list[Symbol]:
        """The facts of the excerpt that keeps these time points."""
        kept = set(keep)
        out = list(self._whole)
        out += [sym for t, is_view, sym in self._timed if t in kept and (is_view or t + 1 in kept)]
        out += [RESUME(t) for t in sorted(kept) if t > 0 and t - 1 not in kept]
        return out
