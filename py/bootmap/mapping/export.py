"""A cognitive map as a graph, for the field's tools: a :mod:`networkx` graph, and the files Gephi, yEd,
Cytoscape and Graphviz open (GraphML, node-link JSON, DOT).

:func:`map_graph` turns a map (a :class:`~.cogmap.CognitiveMap`, or its ``to_dict()`` document, as the
service stores it) into a :class:`networkx.MultiDiGraph`:

Nodes, told apart by ``kind``; every node has a ``label`` (its name, which Gephi shows):

- dstates ``S0, S1, ...`` (``kind="dstate"``): ``view``, ``visits`` (the time points at it), ``misreads``
  (those whose view the map takes as misread), and where the map knows them ``place``, ``path``, ``dir``
  (``pos``/``neg``) and ``heading_deg``;
- places ``P0, ...`` (``kind="place"``): ``dstates``, its dstates joined by spaces, and ``visits``;
- paths ``Pa0, ...`` (``kind="path"``): ``places``, its places in ``pos`` order joined by spaces.

Paths are nodes, not edge attributes: a path has places on it, an order along it and places on either
side, which are relations of the path itself; as a node it carries them as edges, and a layout in Gephi or
yEd draws each path as a hub among its places (colour or filter by ``kind`` to show one level at a time).

Edges, told apart by ``kind``; each has a ``label`` and a key unique in the graph (``e0, e1, ...``: GraphML
edge ids, which Gephi requires to be unique):

- ``turn`` / ``travel``, dstate -> dstate: the actions as the causal level has them. ``action`` is its word:
  ``turn -90`` (the angle of the turn's action type, not the raw reading: the type whose measured mean is
  nearest the reading, or the angle the axioms took it as when the map retyped it), or ``travel`` (the
  causal level names a travel by nothing else); ``count`` is how many times it was taken, ``first_t`` the
  first time point it was taken at, and a travel's ``distance_m`` the mean distance measured. One edge per
  (dstate, action, result).
- ``at``, dstate -> place: the place the dstate is at.
- ``on``, place -> path: the place is on the path; ``pos`` is its position along the path (0 first, in
  the path's ``pos`` direction).
- ``right_of`` / ``left_of``, place -> path: the side of the path the place is on, facing ``pos``.

The graph's own attributes: ``dstates``, ``places``, ``paths`` (counts), ``levels`` (comma-joined),
``found_by``, ``proved_minimal`` and ``unique``.

Every attribute value is a str, int, float or bool (never None: an attribute the map does not know is
left out; lists are joined into strings), so GraphML holds them as typed keys.

Writers: :func:`to_graphml` (networkx's GraphML writer), :func:`to_json_graph` (networkx's node-link JSON,
as d3 and Cytoscape read it) and :func:`to_dot` (Graphviz DOT: networkx writes DOT only through pydot or
pygraphviz, so it is written here, every identifier and value quoted and escaped).
:data:`FORMATS` maps each format's name to its writer.

Example
-------
>>> from bootmap import examples
>>> from bootmap.mapping.api import Mapper
>>> g = map_graph(Mapper().map(examples.notched_rectangle(circuits=2)))
>>> sorted(k for _, k in g.nodes(data="kind")).count("dstate"), g.graph["places"], g.graph["paths"]
(8, 4, 4)
>>> [(v, d["action"], d["count"]) for _, v, d in g.out_edges("S0", data=True) if d["kind"] == "turn"]
[('S1', 'turn -90', 2)]
"""

from __future__ import annotations

import io
import itertools
import json
import re
from typing import Callable

import networkx as nx

__all__ = ["FORMATS", "map_graph", "to_dot", "to_graphml", "to_json_graph", "write"]


def map_graph(cmap) -> nx.MultiDiGraph:
    """The map as a MultiDiGraph (see the module's docstring for its nodes, edges and attributes)."""
    m = cmap if isinstance(cmap, dict) else cmap.to_dict()
    summary = m.get("summary", {})
    g = nx.MultiDiGraph(dstates=len(m["dstates"]), places=len(m.get("places", {})), paths=len(m.get("paths", {})),
                        levels=",".join(summary.get("levels", [])), found_by=str(summary.get("found_by", "")),
                        proved_minimal=bool(summary.get("proved_minimal", True)),
                        unique=bool(summary.get("unique", False)))
    steps = m.get("steps", [])
    misread = {s["t"] for s in m.get("suspect_steps", [])}
    visits: dict[str, int] = {}
    misreads: dict[str, int] = {}
    for s in steps:
        visits[s["dstate"]] = visits.get(s["dstate"], 0) + 1
        misreads[s["dstate"]] = misreads.get(s["dstate"], 0) + (s["t"] in misread)
    for d, info in m["dstates"].items():
        attrs = {"kind": "dstate", "label": d, "view": info["view"], "visits": visits.get(d, 0),
                 "misreads": misreads.get(d, 0)}
        for name in ("place", "path", "dir"):
            if info.get(name) is not None:
                attrs[name] = str(info[name])
        if info.get("heading_deg") is not None:
            attrs["heading_deg"] = int(info["heading_deg"])
        g.add_node(d, **attrs)
    for p, members in m.get("places", {}).items():
        g.add_node(p, kind="place", label=p, dstates=" ".join(members),
                   visits=sum(visits.get(d, 0) for d in members))
    for pa, places in m.get("paths", {}).items():
        g.add_node(pa, kind="path", label=pa, places=" ".join(places))

    keys = (f"e{i}" for i in itertools.count())
    for (src, dst, word), e in _actions(m).items():
        kind = word.split()[0]
        attrs = {"kind": kind, "label": word, "action": word, "count": e["count"], "first_t": e["first_t"]}
        if e["distances"]:
            attrs["distance_m"] = round(sum(e["distances"]) / len(e["distances"]), 6)
        g.add_edge(src, dst, key=next(keys), **attrs)
    for d, info in m["dstates"].items():
        if info.get("place") is not None:
            g.add_edge(d, info["place"], key=next(keys), kind="at", label="at")
    for pa, places in m.get("paths", {}).items():
        for i, p in enumerate(places):
            g.add_edge(p, pa, key=next(keys), kind="on", label=f"on {i}", pos=i)
    for side in ("right_of", "left_of"):
        for p, pa in m.get(side, []):
            g.add_edge(p, pa, key=next(keys), kind=side, label=side.replace("_", " "))
    return g


def _actions(m: dict) -> dict[tuple[str, str, str], dict]:
    """(dstate, next dstate, the action's causal word) -> how many times, first at which t, and the
    travels' measured distances."""
    turn_types = [(a["measured_mean_deg"], a["angle_deg"]) for a in m.get("action_types", []) if a["kind"] == "turn"]
    retyped = {s["t"]: s["abduced_deg"] for s in m.get("retyped_steps", []) if s["kind"] == "turn"}
    steps = m.get("steps", [])
    out: dict[tuple[str, str, str], dict] = {}
    for s, nxt in zip(steps, steps[1:]):
        word, distance = _causal_word(s["t"], s.get("action") or "", turn_types, retyped)
        if word is None:
            continue
        e = out.setdefault((s["dstate"], nxt["dstate"], word), {"count": 0, "first_t": s["t"], "distances": []})
        e["count"] += 1
        if distance is not None:
            e["distances"].append(distance)
    return out


_TURN = re.compile(r"turn ([-+]?[0-9.]+(?:e[-+]?[0-9]+)?)$")
_TRAVEL = re.compile(r"travel ([-+]?[0-9.]+(?:e[-+]?[0-9]+)?) m\b")


def _causal_word(t: int, text: str, turn_types: list[tuple[float, int]], retyped: dict[int, int]):
    """The causal level's word for a step's action (as the map's steps write it: ``turn -87.5``,
    ``travel 4 m, bend +3``) and a travel's measured distance; (None, None) after the last step."""
    if text.startswith("turn"):
        if t in retyped:
            return f"turn {retyped[t]:+d}", None
        found = _TURN.match(text)
        reading = float(found.group(1)) if found else 0.0
        if not turn_types:
            return f"turn {round(reading):+d}", None
        _, angle = min(turn_types, key=lambda ta: (_circular(ta[0] - reading), ta[1]))
        return f"turn {angle:+d}", None
    if text.startswith("travel"):
        found = _TRAVEL.match(text)
        return "travel", float(found.group(1)) if found else None
    return None, None


def _circular(deg: float) -> float:
    return abs((deg + 180.0) % 360.0 - 180.0)


# --- writers -------------------------------------------------------------------------------------------

#: Characters XML 1.0 cannot hold, even as a character reference: replaced by U+FFFD in GraphML.
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def to_graphml(g: nx.MultiDiGraph) -> str:
    """GraphML (networkx's writer, which escapes XML's special characters); the few characters XML cannot
    hold at all (control characters other than tab and newline, lone surrogates) become U+FFFD."""
    def clean(attrs: dict) -> dict:
        return {k: _NOT_XML.sub("\ufffd", v) if isinstance(v, str) else v for k, v in attrs.items()}

    h = nx.MultiDiGraph(**clean(g.graph))
    h.add_nodes_from((n, clean(a)) for n, a in g.nodes(data=True))
    h.add_edges_from((u, v, k, clean(a)) for u, v, k, a in g.edges(keys=True, data=True))
    out = io.BytesIO()
    nx.write_graphml(h, out, encoding="utf-8")
    return out.getvalue().decode("utf-8")


def to_json_graph(g: nx.MultiDiGraph) -> str:
    """Node-link JSON (``networkx.node_link_data``; read back with ``networkx.node_link_graph(data,
    edges="edges")``). ASCII-only: any view name survives any transport."""
    return json.dumps(nx.node_link_data(g, edges="edges"), indent=1) + "\n"


_DOT_SHAPES = {"dstate": "ellipse", "place": "box", "path": "diamond"}
#: The map's attributes whose names Graphviz reads as its own (an edge's spline ``pos``, sfdp's ``levels``),
#: renamed in DOT so that a layout never misreads them.
_DOT_RENAMED = {"pos": "pos_on_path", "levels": "map_levels"}
_DOT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
#: Characters that would end a line or are invisible controls: written as HTML character references,
#: which Graphviz reads in any string (a newline as DOT's own ``\n``).
_DOT_BREAKS = re.compile("[\x00-\x09\x0b-\x1f\x7f-\x9f\u2028\u2029]")
#: An ampersand that Graphviz would read as the start of a character reference.
_DOT_ENTITY = re.compile(r"&(?=#?[A-Za-z0-9]+;)")


def dot_quoted(value) -> str:
    r"""A DOT identifier or value, always double-quoted: backslashes and quotes escaped, a newline as
    ``\n``, other line breaks and controls as character references (and an ``&`` that would start one as
    ``&amp;``), lone surrogates as U+FFFD. A value can never end its string early nor span lines.

    >>> print(dot_quoted('a"b\\'), dot_quoted("x\ny"), dot_quoted("&lt; & \u2028"))
    "a\"b\\" "x\ny" "&amp;lt; & &#8232;"
    """
    if isinstance(value, bool):
        value = "true" if value else "false"
    text = str(value).replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    text = _DOT_ENTITY.sub("&amp;", text)  # "&amp;" stays "&amp;" in Graphviz; a lone & needs nothing
    text = _DOT_BREAKS.sub(lambda c: f"&#{ord(c.group())};", text)
    return '"' + re.sub("[\ud800-\udfff]", "\ufffd", text) + '"'


def _dot_attrs(attrs: dict) -> str:
    names = ((_DOT_RENAMED.get(k, k), v) for k, v in attrs.items())
    return ", ".join(f"{k if _DOT_NAME.match(k) else dot_quoted(k)}={dot_quoted(v)}" for k, v in names)


def to_dot(g: nx.MultiDiGraph, name: str = "cognitive_map") -> str:
    """Graphviz DOT: a ``digraph`` (multi-edges allowed), one line per node and per edge, every identifier
    and value quoted (:func:`dot_quoted`); dstates drawn as ellipses, places as boxes, paths as diamonds.
    The attributes are the graph's, but for two that Graphviz would read as its own: an ``on`` edge's
    ``pos`` is written ``pos_on_path``, the map's ``levels`` ``map_levels``."""
    lines = [f"digraph {dot_quoted(name)} {{"]
    if g.graph:
        lines.append(f"  graph [{_dot_attrs(g.graph)}];")
    for n, attrs in g.nodes(data=True):
        shape = _DOT_SHAPES.get(attrs.get("kind"))
        lines.append(f"  {dot_quoted(n)} [{_dot_attrs({**attrs, **({'shape': shape} if shape else {})})}];")
    for u, v, k, attrs in g.edges(keys=True, data=True):
        lines.append(f"  {dot_quoted(u)} -> {dot_quoted(v)} [{_dot_attrs({'id': k, **attrs})}];")
    lines.append("}")
    return "\n".join(lines) + "\n"


#: Format name -> the writer of a graph in it, and its media type.
FORMATS: dict[str, tuple[Callable[[nx.MultiDiGraph], str], str]] = {
    "graphml": (to_graphml, "application/xml"),
    "json-graph": (to_json_graph, "application/json"),
    "dot": (to_dot, "text/vnd.graphviz"),
}


def write(cmap, fmt: str) -> str:
    """The map (a CognitiveMap or its ``to_dict()`` document) in one of :data:`FORMATS`."""
    try:
        writer, _ = FORMATS[fmt]
    except KeyError:
        raise ValueError(f"unknown graph format {fmt!r}; one of {', '.join(FORMATS)}") from None
    return writer(map_graph(cmap))
