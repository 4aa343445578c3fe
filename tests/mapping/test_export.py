"""The map as a graph file (bootmap.mapping.export): GraphML, node-link JSON and DOT read back as the map
they came from, whatever the views are called; and `bootmap map --format FORMAT -o FILE` writes them."""

from __future__ import annotations

import io
import json
import re
from collections import Counter
from pathlib import Path

import networkx as nx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bootmap.cli import main
from bootmap.mapping.api import Mapper
from bootmap.mapping.export import map_graph, to_dot, to_graphml, to_json_graph, write
from bootmap.tableau import Tableau, Turn, load

PAPER = Path(__file__).resolve().parents[1] / "data" / "paper_notched_rectangle.json"
ODD_VIEWS = ['a"b<c>&d', "Ünïcødé 北 → é", "back\\slash", "&amp; tab\there"]


@pytest.fixture(scope="module")
def paper():
    tableau = load(PAPER)
    return tableau, Mapper().map(tableau)


def causal_word(action) -> str:
    return f"turn {round(action.angle_deg):+d}" if isinstance(action, Turn) else "travel"


def test_graphml_reads_back_as_the_map(paper):
    tableau, cmap = paper
    g = nx.read_graphml(io.BytesIO(to_graphml(map_graph(cmap)).encode()), force_multigraph=True)
    kinds = Counter(kind for _, kind in g.nodes(data="kind"))
    assert kinds == {"dstate": 8, "place": 4, "path": 4}
    assert g.graph["dstates"] == 8 and g.graph["unique"] is True
    for d in cmap.views:
        assert g.nodes[d]["view"] == cmap.views[d] and g.nodes[d]["place"] == cmap.place_of[d]
        assert g.nodes[d]["heading_deg"] == cmap.headings[d]
    # The actions: one edge per dstate, action and result, counted as often as the tableau takes it.
    taken = Counter((cmap.dstate_of[t], causal_word(s.action), cmap.dstate_of[t + 1])
                    for t, s in enumerate(tableau.steps[:-1]))
    edges = {(u, d["action"], v): d for u, v, d in g.edges(data=True) if d["kind"] in ("turn", "travel")}
    assert {k: d["count"] for k, d in edges.items()} == taken
    for d in cmap.views:
        words = [a for (u, a, _) in edges if u == d]
        assert len(words) == len(set(words)) == len({a for (u, a, _) in taken if u == d}) == 1
    assert all(d["kind"] == a.split()[0] for (_, a, _), d in edges.items())
    # Places, paths and sides.
    assert {u: v for u, v, d in g.edges(data=True) if d["kind"] == "at"} == cmap.place_of
    on = {(u, v): d["pos"] for u, v, d in g.edges(data=True) if d["kind"] == "on"}
    assert on == {(p, pa): i for pa, places in cmap.paths.items() for i, p in enumerate(places)}
    assert len(on) == len(cmap.on) == 8
    for side in ("right_of", "left_of"):
        assert sorted((u, v) for u, v, d in g.edges(data=True) if d["kind"] == side) == sorted(getattr(cmap, side))
    # Edge ids are unique (Gephi drops an edge whose id it has seen).
    assert len({k for _, _, k in g.edges(keys=True)}) == g.number_of_edges()


def test_every_attribute_is_graphml_safe(paper):
    g = map_graph(paper[1])
    values = [*g.graph.values(), *(v for _, a in g.nodes(data=True) for v in a.values()),
              *(v for *_, a in g.edges(data=True) for v in a.values())]
    assert values and all(type(v) in (str, int, float, bool) for v in values)


def test_json_graph_round_trips_to_the_same_graph(paper):
    g = map_graph(paper[1])
    h = nx.node_link_graph(json.loads(to_json_graph(g)), edges="edges")
    assert h.is_directed() and h.is_multigraph() and h.graph == g.graph
    assert (h.number_of_nodes(), h.number_of_edges()) == (g.number_of_nodes(), g.number_of_edges()) == (16, 28)
    assert dict(h.nodes(data=True)) == dict(g.nodes(data=True))
    assert sorted(map(repr, h.edges(keys=True, data=True))) == sorted(map(repr, g.edges(keys=True, data=True)))
    assert nx.is_isomorphic(h, g, node_match=dict.__eq__, edge_match=lambda a, b: a == b)


def test_odd_view_names_survive_graphml_and_json(paper):
    """Views are the user's strings: XML's and JSON's special characters, unicode, spaces."""
    tableau, _ = paper
    rename = {f"V{i}": v for i, v in enumerate(ODD_VIEWS)}
    odd = Tableau.from_dict({**tableau.to_dict(), "steps": [
        {**s, "view": rename[s["view"]]} for s in tableau.to_dict()["steps"]]}, "odd")
    cmap = Mapper().map(odd)
    assert sorted(cmap.views.values()) == sorted(ODD_VIEWS * 2)
    back = nx.read_graphml(io.BytesIO(write(cmap, "graphml").encode()))
    assert {d: back.nodes[d]["view"] for d in cmap.views} == cmap.views
    again = nx.node_link_graph(json.loads(write(cmap, "json-graph")), edges="edges")
    assert {d: again.nodes[d]["view"] for d in cmap.views} == cmap.views
    assert write(cmap, "json-graph").isascii()


def test_characters_xml_cannot_hold_become_the_replacement_character(paper):
    m = paper[1].to_dict()
    m["dstates"]["S0"]["view"] = "bell\x07 vt\x0b"
    back = nx.read_graphml(io.BytesIO(to_graphml(map_graph(m)).encode()))
    assert back.nodes["S0"]["view"] == "bell\ufffd vt\ufffd"


def test_turns_are_their_action_types_not_their_readings():
    """A noisy reading is the type the causal level saw; a retyped one, the angle the axioms took."""
    steps = [{"t": 0, "dstate": "S0", "action": "turn -87.5"}, {"t": 1, "dstate": "S1", "action": "turn -93"},
             {"t": 2, "dstate": "S0", "action": "turn +171"}, {"t": 3, "dstate": "S1", "action": "turn -60"},
             {"t": 4, "dstate": "S0", "action": "travel 3.96 m, bend +2"},
             {"t": 5, "dstate": "S1", "action": "travel 4.04 m"}, {"t": 6, "dstate": "S1", "action": ""}]
    m = {"dstates": {d: {"view": d} for d in ("S0", "S1")}, "steps": steps,
         "action_types": [{"kind": "turn", "angle_deg": -90, "measured_mean_deg": -90.2},
                          {"kind": "turn", "angle_deg": 180, "measured_mean_deg": 174.0}],
         "retyped_steps": [{"t": 3, "kind": "turn", "abduced_deg": 180}]}
    edges = {(u, v, d["action"]): d for u, v, d in map_graph(m).edges(data=True)}
    assert {k: d["count"] for k, d in edges.items()} == {
        ("S0", "S1", "turn -90"): 1, ("S1", "S0", "turn -90"): 1, ("S0", "S1", "turn +180"): 1,
        ("S1", "S0", "turn +180"): 1, ("S0", "S1", "travel"): 1, ("S1", "S1", "travel"): 1}
    assert edges["S0", "S1", "travel"]["distance_m"] == 3.96
    assert all(set(d) >= {"kind", "label", "count", "first_t"} for d in edges.values())


# --- DOT: its syntax holds whatever the views are called ---------------------------------------------------

TOKEN = re.compile(r'"(?:[^"\\\n]|\\["\\]|\\(?!["\\]))*"|->|[{}\[\];,=]|[A-Za-z_][A-Za-z0-9_]*|\s+')


def dot_statements(text: str) -> list[list[str]]:
    """DOT's tokens, line by line, lexed as Graphviz does (a quoted string ends at the first quote not
    escaped, backslash pairs consumed); fails on anything else, or on a string spanning lines."""
    lines = []
    for line in text.split("\n"):
        tokens, at = [], 0
        while at < len(line):
            m = TOKEN.match(line, at)
            assert m, f"not DOT at {line[at:at + 20]!r}"
            if not m.group().isspace():
                tokens.append(m.group())
            at = m.end()
        if tokens:
            lines.append(tokens)
    return lines


def dot_value(token: str) -> str:
    """A quoted DOT string's text, its escapes undone (backslash escapes, then character references)."""
    raw = re.sub(r'\\(.)', lambda m: "\n" if m.group(1) == "n" else m.group(1), token[1:-1])
    return re.sub(r"&(?:#(\d+)|amp);", lambda m: chr(int(m.group(1))) if m.group(1) else "&", raw)


def check_dot(text: str, g: nx.MultiDiGraph) -> dict[str, dict[str, str]]:
    """The DOT text's syntax: one statement per line, braces balanced outside strings, every node and
    edge once; -> each node's attributes as read back."""
    assert text.splitlines() == text.rstrip("\n").split("\n")  # no other line break (U+2028, NEL, ...) inside
    lines = dot_statements(text)
    assert lines[0][:2] == ["digraph", lines[0][1]] and lines[0][-1] == "{" and lines[-1] == ["}"]
    depth = 0
    for tokens in lines:
        depth += tokens.count("{") - tokens.count("}")
        assert depth >= 0
    assert depth == 0
    body = lines[2:-1]  # after the graph's own attributes
    nodes = [t for t in body if t[1] == "["]
    edges = [t for t in body if t[1] == "->"]
    assert len(nodes) == g.number_of_nodes() and len(edges) == g.number_of_edges()
    assert len(body) == len(nodes) + len(edges)
    for t in body:
        assert t[-2:] == ["]", ";"] and all(x.startswith('"') for x in t[:t.index("[")] if x != "->")
    read = {}
    for t in nodes:
        attrs = t[2:-2]
        read[dot_value(t[0])] = {attrs[i]: dot_value(attrs[i + 2]) for i in range(0, len(attrs), 4)}
    return read


def test_dot_of_the_paper_map(paper):
    g = map_graph(paper[1])
    text = to_dot(g)
    read = check_dot(text, g)
    assert read["S4"]["view"] == "V0" and read["P0"]["kind"] == "place" and read["Pa0"]["shape"] == "diamond"
    assert ' -> "S1" [id=' in text and "pos_on_path=" in text and "pos=" not in text


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(views=st.lists(st.text(st.characters(exclude_categories=("Cs",)), min_size=1, max_size=12)
                      | st.sampled_from(ODD_VIEWS + ['"', "\\", '\\"', "}", "a\nb", "\u2028", "&#34;"]),
                      min_size=8, max_size=8))
def test_dot_holds_any_view_name(paper, views):
    m = paper[1].to_dict()
    for d, v in zip(sorted(m["dstates"]), views):
        m["dstates"][d]["view"] = v
    g = map_graph(m)
    read = check_dot(to_dot(g), g)
    assert {d: read[d]["view"] for d in m["dstates"]} == {d: m["dstates"][d]["view"] for d in m["dstates"]}


# --- the command ---------------------------------------------------------------------------------------------

def test_map_writes_each_graph_format(tmp_path, capsys):
    readers = {"graphml": lambda p: nx.read_graphml(p, force_multigraph=True),
               "json-graph": lambda p: nx.node_link_graph(json.loads(p.read_text()), edges="edges"),
               "dot": lambda p: check_dot(p.read_text(encoding="utf-8"), map_graph(Mapper().map(load(PAPER))))}
    for fmt, read in readers.items():
        out = tmp_path / f"map.{fmt}"
        assert main(["map", str(PAPER), "--format", fmt, "-o", str(out)]) == 0
        assert capsys.readouterr().out == ""
        got = read(out)
        if fmt != "dot":
            assert Counter(k for _, k in got.nodes(data="kind")) == {"dstate": 8, "place": 4, "path": 4}
        else:
            assert sum(a["kind"] == "dstate" for a in got.values()) == 8
