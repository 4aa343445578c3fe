"""Misread views: which time points the resolver may explain as a misread, and at what cost.

A clustering misreads an image now and then: a robot at dstate S, whose view is V1, records V2. The
exact theory must then explain V2 as a dstate of its own, and determinism carries the contradiction
forward: one misread in 400 steps can make a map of 27 dstates out of 8, or none. Robust abduction
lets the solver take a few views as misreads, each at a cost, and finds the map with the fewest
dstates plus the cost of its misreads (core/partition.lp): a misread is called only where reading the
view as seen would need more dstates than the misread costs.

Which views may be misreads (the *suspects*) is chosen here, from the tableau alone, so that clean
experience is resolved exactly as before and the search stays small:

* a view seen where the experience around it says otherwise: after the same one or two views and
  actions, or before the same one or two actions and views, other views were seen at least three times
  as often (a misread breaks both transitions; where views alias, one of them may look ordinary; the
  first and the last time point have one side, and are read by it);
* a view with one or two images in a tableau whose views have many (:func:`rare_views`):
  as likely a misread image as a place, it is cheap to call a misread (half a dstate).

Costs are in units where a dstate costs ``DSTATE_COST`` (4). A suspect costs ``MISREAD_COST`` (10: two
and a half dstates). Where the tableau has images, an image deep inside its view's cluster costs more to
call a misread than one near the boundary with another view (the clustering's own margin): from 3 at the
boundary up to 18. A suspect surprising on one side only costs more where the other side's contexts
were seen only a few times (``FULL_EVIDENCE``).

Example
-------
>>> views = list("ABCD" * 25)
>>> views[21] = "A"                       # a B read as A: it follows A and precedes C, unlike any other A
>>> [(s.t, s.cost, s.expected, s.clear) for s in find_suspects(views, ["turn"] * 100)]
[(20, 60, ('D',), False), (21, 10, ('B',), True), (22, 60, ('A', 'B'), False)]

Only t21 is surprising on both sides; its neighbours are surprising on the side that sees t21.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from dataclasses import dataclass
from typing import Collection, Hashable, Sequence

import numpy as np
from clingo import Symbol

from ..tableau import Tableau
from .vocabulary import action_word


#: What calling a suspect view a misread costs when nothing else is known: 2.5 dstates.
MISREAD_COST = 10
#: ... for a view with one or two images in a tableau whose views have ``RARE_AMONG`` on average: half a
#: dstate. (In a short tableau every view is seen only a few times: none is rare.)
RARE_VIEW_COST, RARE_AMONG = 2, 10
#: A view seen in a context at most twice is surprising when it is at most this share of the context's
#: visits on one side (before or after it); clearly so when it is at most ``WEAK`` on the other. (Clear
#: suspects hold about 90% of the misreads of a 600-step exploration, with few others; all suspects 98%,
#: at eight suspects per misread.)
STRONG = 0.25
WEAK = 0.5
#: A view surprising on one side only is a suspect only in a tableau this long: short ones repeat too
#: little (and a search for misreads there only slows the exact map down: 30-step aliased walks timed
#: out). Surprise on both sides is evidence at any length: in the paper's room, one misread view at the
#: 65th step read as seen set every time point apart (66 dstates for 8, 3.5 s a resolve, and a search
#: that timed out at 20 s on 7 of 20 seeds of 97 steps with two misreads); suspected, the true map in
#: 0.07 s.
MIN_STEPS = 100
#: ... and only where the robot has repeated its experience: at least this many time points per class
#: of time points (view and heading). Early exploration (2-4 per class) visits most dstates once or
#: twice, and a search for misreads there cost seconds to minutes for none (a 105-step exploration
#: prefix: 43 s); a 600-step exploration with 2% misreads has 9-12 per class, the paper's tableau 45.
MIN_VISITS = 5
#: A view seen in a context at most this many times is read by its share of the context's visits; one
#: seen more often is ordinary there.
SEEN_RARELY = 2
#: Clear suspects are read as their contexts expect, and found again on the views so read, at most so many
#: times (:func:`read_as_expected`).
EXPECTED_ROUNDS = 5
#: Why a view became a suspect where reading the clear suspects as expected explained the experience.
AS_EXPECTED = "misread, where the views around the clear suspects, read as expected, show it"
#: Why a rare view is suspect.
RARE_VIEW = "a view with one or two images"
#: Why a view no rule here suspected became a suspect (the resolver finds these: :mod:`.search.abduction`).
GHOST = "a dstate of its own in a first map"
#: ... or became one beside a suspect, where the suspects could not explain the experience.
BESIDE = "next to a suspect, where the suspects alone could not explain the experience"
#: A misread costs more where its contexts showed the other views fewer times than this (3 times: double).
FULL_EVIDENCE = 6
#: With images, the cost runs from the boundary's to the cluster core's.
MARGIN_COSTS = (3, 18)


@dataclass(frozen=True)
class Suspect:
    """A time point whose view the solver may take as a misread.

    Attributes
    ----------
    t : int
        The time point.
    cost : int
        What calling it a misread costs (a dstate costs ``DSTATE_COST``).
    expected : tuple
        The views the experience around it suggests instead (empty: any view).
    reason : str
        Why it is suspect, for people.
    evidence : tuple of str
        What was seen in the contexts that make it surprising, for people.
    clear : bool
        Surprising on both sides of it (or a rare view). A misread view usually is; where views alias,
        one side may look ordinary, so the resolver widens its search to the others when the clear
        suspects do not explain the experience.
    """

    t: int
    cost: int
    expected: tuple
    reason: str
    clear: bool = True
    evidence: tuple[str, ...] = ()


def find_suspects(views: Sequence[Hashable], actions: Sequence[Hashable],
                  images: np.ndarray | None = None) -> list[Suspect]:
    """The suspect time points of a tableau, in order.

    Parameters
    ----------
    views : sequence
        The view seen at each time point.
    actions : sequence
        The action from each time point to the next, as the axioms name it (one fewer than views, or
        as many with the last ignored).
    images : array (n, d), optional
        The images the views were clustered from; their margins set the costs.
    """
    n = len(views)
    # Views and actions as small ints: the contexts hash tuples of them, and a clingo symbol's hash
    # is a call into clingo.
    view_ids, action_ids = _ids(views), _ids(actions)
    contexts = _Contexts([view_ids[v] for v in views], [action_ids[a] for a in actions[:n]],
                         {i: v for v, i in view_ids.items()}, {i: a for a, i in action_ids.items()})
    rare = {t for ts in rare_views(views, typical=RARE_AMONG).values() for t in ts}
    costs = _margin_costs(views, images)
    # How surprising each view is after what came before it, and before what came after: read once.
    around = [(contexts.before(t), contexts.after(t)) for t in range(n)]
    sides_of = [[side for side in pair if side is not None] for pair in around]
    surprising = [_surprising(sides, n) for sides in sides_of]
    clear_at = {t for t in range(n) if _clear_suspect(sides_of[t], n)}
    # The first of two misreads in a row: its side towards the second saw that misread (a context never
    # seen, so ordinary), and its other side is all the evidence there is. (A view with one or two images
    # is as likely a place seen once as a misread: the time points beside it are read as they are.)
    beside = {t for t in range(n) if not surprising[t] and _beside_clear(around[t], t, clear_at - rare)}
    surprising = [surprising[t] or t in beside for t in range(n)]
    clear_at |= beside
    found = []
    for t in range(n):
        sides = sides_of[t]
        expected = _expected(_trusted(around[t], t, clear_at)) or _expected(sides)
        if t in rare:
            found.append(Suspect(t, RARE_VIEW_COST, expected, RARE_VIEW))
        elif surprising[t]:
            base = MISREAD_COST if costs is None else int(costs[t])
            clear = t in clear_at
            # Where one side looks ordinary, thin evidence on the other (a context seen only a few
            # times) makes a misread the dearer explanation. Surprise on both sides is evidence enough:
            # the search still takes a misread only where it saves dstates.
            evidence = min(side[2] for side in sides)
            cost = base if clear else int(round(base * max(1.0, FULL_EVIDENCE / max(evidence, 1))))
            reason = ("unlike what the experience around it shows" + ("" if clear else " on one side")
                      if len(sides) == 2 else
                      f"unlike what the experience {'before' if t else 'after'} it shows (an end of the experience)")
            found.append(Suspect(t, cost, expected, reason, clear,
                                 tuple(contexts.describe(side[3]) for side in sides)))
    return found


def _trusted(around: tuple, t: int, clear_at: set[int]) -> list:
    """Of t's sides (before, after; None where there is nothing), those whose contexts say what t's view
    should have been: a side whose neighbour is itself clearly surprising (two misreads in a row) saw
    that neighbour's misread, so what it expects is not evidence (a true L.RB read as LFRB, just before
    a LFR. read as LF.B, was expected only as .FRB, and no map with its misreads could explain it).
    Empty where both neighbours are; where the sides left expect no other view, t is ordinary there:
    the caller then reads both sides."""
    return [side for side, neighbour in zip(around, (t - 1, t + 1))
            if side is not None and neighbour not in clear_at]


def _beside_clear(around: tuple, t: int, clear_at) -> bool:
    """t's view is strongly surprising on one side (``STRONG``), and its other side is next to a clear
    suspect: a side that saw a misread is no evidence that t's view is ordinary there."""
    before, after = around
    return ((before is not None and after is not None)
            and ((t + 1 in clear_at and before[0] <= STRONG) or (t - 1 in clear_at and after[0] <= STRONG)))


def _clear_suspect(sides: list, n: int) -> bool:
    """Surprising in its contexts (:func:`_surprising`), and on both sides (:func:`_clear`)."""
    return _surprising(sides, n) and _clear(sides)


def _clear(sides: list) -> bool:
    """Surprising on both sides: at most ``WEAK`` on the less surprising one."""
    return len(sides) == 2 and max(side[0] for side in sides) <= WEAK


def _surprising(sides: list, n: int) -> bool:
    """A view is a suspect for its contexts: a view seen where, on one side at least, other views were
    seen far more often (on one side only, in a tableau long enough to tell: ``MIN_STEPS``). The first
    and the last time point have one side: there it is all the evidence, at any length (a stream's newest
    view, misread, would otherwise be read as seen until the next step gives it a side after)."""
    strongly = bool(sides) and min(side[0] for side in sides) <= STRONG
    return strongly and (len(sides) == 1 or n >= MIN_STEPS or _clear(sides))


class SuspectWatch:
    """Whether :func:`find_suspects` names any time point of a growing tableau (labels only, no images),
    kept current as steps are appended: what a step changes are the contexts that end at it, so only
    the time points that share one of those contexts (and the last few) are looked at again.

    >>> watch = SuspectWatch()
    >>> views = list("ABCD" * 25)
    >>> views[21] = "A"
    >>> for t, v in enumerate(views):
    ...     watch.append(v, None if t == 0 else "turn")
    >>> sorted(watch.suspects) == [s.t for s in find_suspects(views, ["turn"] * 100)]
    True
    """

    def __init__(self):
        self._view_ids: dict = {}
        self._action_ids: dict = {}
        self.contexts = _Contexts([], [], {}, {}, index=True)
        self.suspects: set[int] = set()
        self.clear_suspects: set[int] = set()  # the suspects that are clear ones (:meth:`clear`)
        self.rare: set = set()
        self._at: dict[int, list[int]] = {}  # view id -> its time points

    @classmethod
    def of(cls, views: Sequence[Hashable], actions: Sequence[Hashable]) -> "SuspectWatch":
        """The watch of a whole tableau at once (its views, and the actions between them)."""
        watch = cls()
        for t, view in enumerate(views):
            watch._add(view, actions[t - 1] if t else None)
        n = len(views)
        watch.rare = _rare(watch._at, n, typical=RARE_AMONG)
        watch.suspects = {t for t in range(n) if watch._suspect(t, n)}
        watch.clear_suspects = {t for t in watch.suspects if watch.clear(t)}
        return watch

    def _suspect(self, t: int, n: int) -> bool:
        """Does :func:`find_suspects` name t (of ``n`` time points)?"""
        contexts = self.contexts
        if contexts.views[t] in self.rare:
            return True
        around = (contexts.before(t), contexts.after(t))
        sides = [side for side in around if side is not None]
        if _surprising(sides, n):
            return True
        if len(sides) < 2 or min(side[0] for side in sides) > STRONG:
            return False  # no side strongly surprising: no neighbour can make it a suspect
        clear_at = {u for u in (t - 1, t + 1)
                    if 0 <= u < n and contexts.views[u] not in self.rare and _clear_suspect(contexts.sides(u), n)}
        return _beside_clear(around, t, clear_at)

    def _add(self, view: Hashable, action_before: Hashable | None) -> set[int]:
        v = self._view_ids.setdefault(view, len(self._view_ids))
        self.contexts.view_names[v] = view
        a = None
        if action_before is not None:
            a = self._action_ids.setdefault(action_before, len(self._action_ids))
            self.contexts.action_names[a] = action_before
        changed = self.contexts.append(v, a)
        self._at.setdefault(v, []).append(len(self.contexts.views) - 1)
        return changed

    @property
    def rare_names(self) -> set:
        """The rare views (:func:`rare_views`), by label."""
        return {self.contexts.view_names[v] for v in self.rare}

    def clear(self, t: int) -> bool:
        """Is suspect t a clear one (:attr:`Suspect.clear`): a rare view, or surprising on both sides?"""
        return self.contexts.views[t] in self.rare or _clear(self.contexts.sides(t))

    def append(self, view: Hashable, action_before: Hashable | None) -> None:
        """The next time point's view, and the action that led to it (None for the first)."""
        changed = self._add(view, action_before)
        n = len(self.contexts.views)
        again = set(changed) | set(range(max(0, n - 4), n))
        rare = _rare(self._at, n, typical=RARE_AMONG)
        for x in rare ^ self.rare:
            again.update(self._at[x])
        self.rare = rare
        # A time point's neighbours read it (a suspect beside a clear one: _beside_clear).
        again |= {u for t in again for u in (t - 1, t + 1) if 0 <= u < n}
        if n == MIN_STEPS:
            again = range(n)
        for t in again:  # (a suspect's sides, and whether its view is rare, change only for these)
            if self._suspect(t, n):
                self.suspects.add(t)
                if self.clear(t):
                    self.clear_suspects.add(t)
                else:
                    self.clear_suspects.discard(t)
            else:
                self.suspects.discard(t)
                self.clear_suspects.discard(t)


def read_as_expected(views: Sequence[Hashable], actions: Sequence[Hashable],
                     rounds: int = EXPECTED_ROUNDS) -> tuple[list, list[int]]:
    """The views with each clear suspect whose contexts expect one view read as that view, and the time
    points so read. A misread next to another hides it (each side of one sees the other): once the clearer
    one is read as expected, the other shows; so the suspects are found again on the views so read, at
    most ``rounds`` times, until none changes. A guess, not an explanation: the resolver weighs it
    (:meth:`.search.abduction.MisreadAbduction._as_expected`).

    >>> views = list("ABCD" * 25)
    >>> views[21] = "A"
    >>> read, changed = read_as_expected(views, ["turn"] * 100)
    >>> changed, read[21]
    ([21], 'B')
    """
    read, changed = list(views), []
    for _ in range(rounds):
        fresh = [s for s in find_suspects(read, actions)
                 if s.clear and len(s.expected) == 1 and s.reason != RARE_VIEW and s.t not in changed]
        if not fresh:
            break
        for s in fresh:
            read[s.t] = s.expected[0]
            changed.append(s.t)
    return read, sorted(changed)


def context_views(views: Sequence[Hashable], actions: Sequence[Hashable], times: Sequence[int]) -> dict:
    """For each of ``times``, the other views seen in its contexts of one step (after the same view and
    action, before the same action and view): what a misread there most likely hid. Empty where the
    contexts show no other view.

    >>> context_views(list("ABAB") + ["C"] + list("BAB"), ["turn"] * 8, [4])
    {4: ('A',)}
    """
    view_ids, action_ids = _ids(views), _ids(actions)
    names = {i: v for v, i in view_ids.items()}
    contexts = _Contexts([view_ids[v] for v in views], [action_ids[a] for a in actions[:len(views)]],
                         names, {i: a for a, i in action_ids.items()})
    out = {}
    for t in times:
        seen: set[int] = set()
        for ahead in (False, True):
            key = contexts._key(t, 1, ahead)
            if key is not None:
                seen |= {v for v in contexts.seen[key] if v != contexts.views[t]}
        out[t] = tuple(sorted((names[v] for v in seen), key=str))
    return out


def skipping_views(views: Sequence[Hashable], actions: Sequence[Hashable], times: Sequence[int],
                   suspects: Collection[int]) -> dict:
    """For each of ``times`` next to a suspect, the other views seen where the same actions lead on from
    (or back to) the view beyond that suspect: its context with the suspect skipped. A misread next to a
    misread has a context that shows what the other misread showed; skipping it reads what the robot saw
    around both.

    >>> skipping_views(list("ABCABCAXY"), ["turn"] * 8, [8], {7})
    {8: ('C',)}
    """
    n = len(views)
    # What was seen two actions after a view, and two actions before one, by the actions taken between.
    after: dict = defaultdict(set)
    before: dict = defaultdict(set)
    for u in range(2, n):
        after[views[u - 2], actions[u - 2], actions[u - 1]].add(views[u])
        before[views[u], actions[u - 2], actions[u - 1]].add(views[u - 2])
    out = {}
    for t in times:
        seen: set = set()
        if t - 1 in suspects and t >= 2:
            seen |= after[views[t - 2], actions[t - 2], actions[t - 1]]
        if t + 1 in suspects and t + 2 < n:
            seen |= before[views[t + 2], actions[t], actions[t + 1]]
        seen = seen - {views[t]}
        if seen:
            out[t] = tuple(sorted(seen, key=str))
    return out


def rare_views(views: Sequence[Hashable], at_most: int = 2, typical: int = 5) -> dict:
    """Views with at most ``at_most`` images in a tableau whose views have ``typical`` or more on average:
    view -> its time points. Such a view is as likely a misread image (a drop-out left unrepaired, a
    passer-by) as a place, and reading it as seen makes it a dstate of its own.

    >>> rare_views(["V0", "V1"] * 10 + ["V2"])
    {'V2': [20]}
    """
    at: dict = {}
    for t, v in enumerate(views):
        at.setdefault(v, []).append(t)
    return {v: at[v] for v in _rare(at, len(views), at_most, typical)}


def _rare(at: dict, n: int, at_most: int = 2, typical: int = 5) -> set:
    """Of the views seen at these time points (view -> time points) in a tableau of ``n``, the rare ones
    (:func:`rare_views`)."""
    if n < typical * len(at):
        return set()
    return {v for v, ts in at.items() if len(ts) <= at_most}


def has_images(tableau: Tableau) -> bool:
    """Every step of the tableau has an image (its views were, or can be, clustered from them)."""
    return bool(tableau.steps) and all(s.image is not None for s in tableau.steps)


def rare_clustered_views(tableau: Tableau) -> bool:
    """Some view of a tableau of images has only one or two of them (:func:`rare_views`): a suspect. A
    label given without an image is the user's word (a landmark seen once), not a suspect."""
    return has_images(tableau) and bool(rare_views(tableau.views, typical=RARE_AMONG))


class _Contexts:
    """What views were seen in which contexts: after the last one to three (view, action) pairs, and
    before the next one to three (action, view) pairs. One step of context is often ambiguous where views
    alias (many dstates look alike and lead on to different views); longer ones seldom are."""

    DEPTHS = (1, 2, 3)
    #: A longer context counts once it has been seen this often.
    MIN_SEEN = 4

    def __init__(self, views: Sequence[int], actions: Sequence[int], view_names: dict, action_names: dict,
                 index: bool = False):
        self.views, self.actions = list(views), list(actions)
        self.view_names, self.action_names = view_names, action_names
        self.seen: dict = {}
        # Each context's reading of a view (:meth:`_side`), kept until the context is seen again: many time
        # points share a context and a view.
        self._read: dict = {}
        # With an index, which time points each context was seen at (to look at them again on append).
        self.at: dict | None = {} if index else None
        for t in range(len(views)):
            for key in self._keys(t):
                self._count(key, t)

    def _count(self, key, t: int) -> None:
        seen = self.seen.get(key)
        if seen is None:
            seen = self.seen[key] = Counter()
        seen[self.views[t]] += 1
        self._read.pop(key, None)
        if self.at is not None:
            self.at.setdefault(key, {}).setdefault(self.views[t], []).append(t)

    def _reread(self, key, depth: int) -> list[int]:
        """The time points whose reading of a context may change now that it was seen once more: those
        whose view it has seen at most once more than ``SEEN_RARELY`` (beyond that a view is ordinary
        there whatever else is seen), or all of them once a longer context is seen often enough to count."""
        seen, at = self.seen[key], self.at[key]
        if depth > 1 and sum(seen.values()) == self.MIN_SEEN:
            return [t for ts in at.values() for t in ts]
        return [t for v, ts in at.items() if seen[v] <= SEEN_RARELY + 1 for t in ts]

    def append(self, view: int, action_before: int | None) -> set[int]:
        """One more time point (its view, and the action from the one before). Returns the time points
        whose contexts were seen again, so may read differently: the contexts that end at the new
        time point (the views before it, and what the last three saw after them)."""
        if self.views:
            del self.actions[len(self.views) - 1:]  # an action after the last time point is not experience
            self.actions.append(action_before)
        self.views.append(view)
        n = len(self.views)
        changed: set[int] = set()
        ending = [(n - 1, depth, False) for depth in self.DEPTHS] + [(n - 1 - depth, depth, True) for depth in self.DEPTHS]
        for t, depth, ahead in ending:
            key = self._key(t, depth, ahead) if t >= 0 else None
            if key is not None:
                self._count(key, t)
                if self.at is not None:
                    changed.update(self._reread(key, depth))
        return changed

    def sides(self, t: int) -> list:
        """How surprising t's view is after what came before it, and before what came after (a side
        is left out where there is nothing on it)."""
        return [side for side in (self.before(t), self.after(t)) if side is not None]

    def _key(self, t: int, depth: int, ahead: bool):
        lo, hi = (t + 1, t + 1 + depth) if ahead else (t - depth, t)
        if lo < 0 or hi > len(self.views):
            return None
        acts = tuple(self.actions[lo - 1:hi - 1]) if ahead else tuple(self.actions[lo:hi])
        return ahead, tuple(self.views[lo:hi]), acts

    def _keys(self, t: int):
        for depth in self.DEPTHS:
            for ahead in (False, True):
                key = self._key(t, depth, ahead)
                if key is not None:
                    yield key

    def before(self, t: int):
        return self._side(t, ahead=False)

    def after(self, t: int):
        return self._side(t, ahead=True)

    def _side(self, t: int, ahead: bool):
        """The most surprising reading of t's view in its contexts on one side (None at the end): its
        share, the other views seen there, how often, and the context's key (:meth:`describe` words it:
        only suspects need the words, and they are most of the cost)."""
        found = []
        view = self.views[t]
        for depth in self.DEPTHS:
            key = self._key(t, depth, ahead)
            if key is None:
                continue
            read = self._read.setdefault(key, {})
            if view not in read:
                seen = self.seen[key]
                read[view] = (*_surprise(seen, view), key) if depth == 1 or seen.total() >= self.MIN_SEEN else None
            if read[view] is not None:
                found.append(read[view])
        if not found:
            return None
        share, others, n, key = min(found, key=lambda f: (f[0], -f[2]))
        return share, tuple(self.view_names[v] for v in others), n, key

    def describe(self, key) -> str:
        """A context and what was seen in it, e.g. "after V0, turn -90: V1 12 times, V3 once"."""
        ahead, views, actions = key
        views = [self.view_names[v] for v in views]
        actions = [self.action_names[a] for a in actions]
        steps = [x for pair in (zip(actions, views) if ahead else zip(views, actions)) for x in pair]
        words = ", ".join(action_word(x) if isinstance(x, Symbol) else str(x) for x in steps)
        counts = ", ".join(f"{self.view_names[v]} {'once' if n == 1 else 'twice' if n == 2 else f'{n} times'}"
                           for v, n in self.seen[key].most_common())
        return f"{'before' if ahead else 'after'} {words}: {counts}"


def _surprise(seen: Counter, view) -> tuple[float, tuple, int]:
    """How rarely ``view`` was seen in a context (its share, or 1 when seen there three times or more),
    the views seen there instead, and how often they were."""
    share = seen[view] / sum(seen.values()) if seen[view] <= SEEN_RARELY else 1.0
    return share, tuple(v for v in seen if v != view), sum(seen.values()) - seen[view]


def _ids(items: Sequence[Hashable]) -> dict:
    """Each distinct item's small int, by first appearance."""
    ids: dict = {}
    for x in items:
        ids.setdefault(x, len(ids))
    return ids


def _expected(sides: list) -> tuple:
    """The views both contexts saw instead, else either saw, most often seen first."""
    sets = [set(side[1]) for side in sides if side[1]]
    if not sets:
        return ()
    return tuple(sorted(set.intersection(*sets) or set.union(*sets), key=str))


def _margin_costs(views: Sequence[Hashable], images: np.ndarray | None) -> np.ndarray | None:
    """Per time point, the cost of calling its view a misread, from how deep its image lies in its
    view's cluster: (distance to the nearest other view's centre - to its own) / (their sum), in [0, 1]
    inside the cluster, mapped onto ``MARGIN_COSTS``. None without images."""
    if images is None or len(images) != len(views):
        return None
    labels = sorted(set(views), key=str)
    if len(labels) < 2:
        return None
    index = {v: i for i, v in enumerate(labels)}
    y = np.array([index[v] for v in views])
    centres = np.stack([images[y == i].mean(axis=0) for i in range(len(labels))])
    d = np.linalg.norm(images[:, None, :] - centres[None, :, :], axis=2)
    own = d[np.arange(len(y)), y]
    d[np.arange(len(y)), y] = np.inf
    other = d.min(axis=1)
    margin = np.clip((other - own) / np.maximum(other + own, 1e-12), 0.0, 1.0)
    low, high = MARGIN_COSTS
    return np.rint(low + (high - low) * margin).astype(int)
