"""Loop closing: a map from the robot's own odometry, checked by every axiom.

The paper's map is the one with the fewest dstates: two time points are one dstate unless the
experience proves them different. That needs views that tell dstates apart. On a real log they barely
do (the Killian log's views are near chance, and most of its dstates are seen once), so the fewest
dstates merge visits the experience merely fails to tell apart, and the search for them does not end.

Here the robot's odometry proposes which visits are one dstate, and the axioms dispose:

1. Every visit starts as a dstate of its own.
2. Two visits facing one way (the metrical level's heading) are proposed as one dstate where
   odometry says so: **near**, within ``radius_m`` plus ``near_share`` of the distance driven between
   them (dead reckoning drifts slowly: a short loop closes tightly); or **retraced**, the robot did the
   same actions (turn types, travel length types) for ``context`` steps before and after them, they
   show one view, and they are within ``radius_m`` plus ``drift_share`` of the distance driven (a long
   loop driven again, whose ends dead reckoning has drifted apart). Longest context first, then
   nearest in metres. After odometry's, the laser's: **recognised**, a place match the tableau carries
   (``meta.place_matches``: a log's visits' local maps matched and verified by the places around them,
   :mod:`bootmap.surroundings`) scoring at least ``match_score``, within the drift bound, whose turns'
   middles are one place once their scans are put together. Strongest match first. A near or retraced
   pair is not proposed where the laser matched the later visit's place with earlier visits, none of them the
   earlier visit's place (:meth:`Closing.elsewhere`).
3. A proposal is folded as the causal level demands (the same action from one dstate reaches one
   dstate: merge and fold, as RPNI does); every pair of visits the fold joins must face one way and
   lie within the drift bound, or the proposal is dropped. A near proposal says the visits are in one
   place: every pair of visits it makes one dstate must be near by the same bound, not only the pair
   proposed (complete linkage, as the truth's places are made; a chain of near pairs along a corridor
   is not one place). The joins determinism forces then are held to the drift bound.
4. What is left is checked by clingo with every axiom file (the partition fixed, ``fixed/2``), views
   taken as soft evidence: each dstate shows the view most of its visits show, and the other visits
   are listed as misreads (``suspect_steps``). A proposal the axioms reject is dropped.
5. Then again, with dead reckoning re-anchored at the joins made (:mod:`.anchoring`, as a pose graph
   corrects a drive where its loops close): between two visits, the drift that counts is that of the
   shortest way through the drive and the joins (a join counted as the drive over which a near pair may
   drift a place radius), and the visits lie where odometry puts them along that way. The pairs that
   become near, retraced or recognised are proposed (none proposed before) and checked as above, until a
   round joins nothing.

The result satisfies every axiom but is not proved minimal (``minimal`` is False): it is the map
odometry supports, not the smallest one the views allow. A tableau whose steps carry ``odometry``
(a log) is dead-reckoned from it; otherwise from its actions (turns on the spot, as the simulator's,
at the learned types' angles). :meth:`LoopCloser.explain` says why two time points are one dstate of
the map (each join, proposed by odometry or the laser, or forced) or not (headings, odometry, the rules
that reject joining them, or no evidence); :func:`closes_loops` says when loop closing is the mapper (a log's tableau,
``passes_through``).

Loop closing itself is :mod:`.closing`; dead reckoning re-anchored at its joins is :mod:`.anchoring`;
saying why two time points are one dstate of its map or not is :mod:`.explain`.

Example
-------
Two laps of a square whose corners look alike: views say nothing, odometry closes the loop.

>>> from bootmap.tableau import Tableau
>>> lap = [{"view": "corner", "action": {"type": "travel", "distance_m": 5}},
...        {"view": "corner", "action": {"type": "turn", "angle_deg": 90}}] * 4
>>> square = Tableau.from_dict({"format": "bootmap.tableau/1", "steps": lap * 2 + [{"view": "corner"}]})
>>> cmap = LoopCloser().resolve(square)
>>> cmap.n_dstates, cmap.n_places, cmap.minimal
(8, 4, False)
"""

from .closing import MAPPERS, LoopCloser, closes_loops, dead_reckoning
from .explain import Join, LoopExplanation

__all__ = ["LoopCloser", "LoopExplanation", "MAPPERS", "closes_loops", "dead_reckoning", "Join"]
