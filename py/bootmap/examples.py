"""Hand-made tableaux with known answers: the paper's notched rectangle and small worlds that
each exercise one part of the theory. Every builder returns a :class:`~bootmap.tableau.Tableau`
whose steps carry the true dstate in ``truth``.
"""

from __future__ import annotations

from .tableau import Step, Tableau, Travel, Turn


def _tableau(rows: list[tuple[str, object, str]], world: str) -> Tableau:
    return Tableau(tuple(Step(view=v, action=a, truth=s) for v, a, s in rows), world)  # type: ignore[arg-type]


def notched_rectangle(circuits: int = 50, clockwise: bool = True) -> Tableau:
    """The paper's tableau (Figure 2): circuits of a 5 m x 3 m room, 8 time points a circuit.

    Views V0..V3 as in the paper; dstates S0..S7, one before and one after the turn at each corner.
    Counter-clockwise circuits turn left and see the mirror images (views W0..W3).
    """
    sign, prefix = (-1, "V") if clockwise else (1, "W")
    cycle = [Turn(90.0 * sign), Travel(4.0), Turn(90.0 * sign), Travel(2.0)]
    rows = [(f"{prefix}{t % 4}", cycle[t % 4], f"S{t % 8}") for t in range(8 * circuits)]
    rows.append((f"{prefix}0", None, "S0"))
    return _tableau(rows, "notched_rectangle" + ("" if clockwise else "_ccw"))


def square_room(circuits: int = 3) -> Tableau:
    """Clockwise circuits of a square room whose four corners look alike: two views, 8 true dstates.

    The topological rules alone accept a triangle (6 dstates); the metrical level rejects it
    because three right turns of 90 degrees do not make a full turn.
    """
    rows = []
    for t in range(8 * circuits):
        corner = t // 2 % 4
        rows.append(("corner" if t % 2 == 0 else "wall", Turn(-90.0) if t % 2 == 0 else Travel(3.0),
                     f"C{corner}{'in' if t % 2 == 0 else 'out'}"))
    rows.append(("corner", None, "C0in"))
    return _tableau(rows, "square_room")


def corridor(laps: int = 2, middle: bool = True) -> Tableau:
    """A corridor walked end to end, turning around at both dead ends.

    West end W, (optionally) a doorway M to the north in the middle, east end E. Views name what is
    open to the left, front, right and back ('.' where closed). Truth: place and heading.
    """
    out_e = [(".F..", "W:0")] + ([("LF.B", "M:0")] if middle else []) + [("...B", "E:0")]
    out_w = [(".F..", "E:180")] + ([(".FRB", "M:180")] if middle else []) + [("...B", "W:180")]
    rows = []
    for _ in range(laps):
        for leg in (out_e, out_w):
            for i, (v, s) in enumerate(leg):
                rows.append((v, Travel(4.0) if i < len(leg) - 1 else Turn(180.0), s))
    rows.append((".F..", None, "W:0"))
    return _tableau(rows, "corridor")


def one_way_run(junctions: int = 5) -> Tableau:
    """A long hallway with look-alike side openings, travelled one way: every junction shows view J.

    Causal and metrical axioms accept a single dstate that travels to itself; the topological order
    (a place is never ahead of itself along a path) keeps every junction apart.
    """
    rows = [("J", Travel(3.0), f"J{i}") for i in range(junctions - 1)] + [("J", None, f"J{junctions - 1}")]
    return _tableau(rows, "one_way_run")
