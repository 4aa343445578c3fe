"""GET /tableaux/{id}/map/graph: the stored map as GraphML, node-link JSON or DOT, from the real server."""

from __future__ import annotations

import io
from collections import Counter

import networkx as nx


def kinds(g: nx.MultiDiGraph) -> Counter:
    return Counter(kind for _, kind in g.nodes(data="kind"))


def test_the_map_is_served_in_each_graph_format(client, paper_id):
    m = client.get(f"/tableaux/{paper_id}/map").json()
    url = f"/tableaux/{paper_id}/map/graph"

    r = client.get(url, params={"format": "graphml"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/xml"
    g = nx.read_graphml(io.BytesIO(r.content), force_multigraph=True)
    assert kinds(g) == {"dstate": 8, "place": 4, "path": 4}
    at = {u: v for u, v, d in g.edges(data=True) if d["kind"] == "at"}
    assert at == {d: x["place"] for d, x in m["dstates"].items()}
    assert client.get(url).content == r.content  # GraphML is the default

    r = client.get(url, params={"format": "json-graph"})
    assert r.status_code == 200 and r.headers["content-type"] == "application/json"
    h = nx.node_link_graph(r.json(), edges="edges")
    assert kinds(h) == kinds(g) and h.number_of_edges() == g.number_of_edges()
    assert sum(d["count"] for *_, d in h.edges(data=True) if d["kind"] in ("turn", "travel")) == len(m["steps"]) - 1

    r = client.get(url, params={"format": "dot"})
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/vnd.graphviz")
    assert r.text.startswith('digraph "cognitive_map" {') and r.text.rstrip().endswith("}")
    assert '"S0" -> "S1" [' in r.text and r.text.count("\n") == 1 + 1 + 16 + g.number_of_edges() + 1


def test_an_unknown_format_or_tableau_is_refused(client, paper_id):
    r = client.get(f"/tableaux/{paper_id}/map/graph", params={"format": "gexf"})
    assert r.status_code == 422 and r.headers["content-type"].startswith("application/problem+json")
    assert client.get("/tableaux/999999/map/graph").status_code == 404


def test_the_route_is_documented(client):
    op = client.get("/openapi.json").json()["paths"]["/tableaux/{tableau_id}/map/graph"]["get"]
    assert op["summary"] and set(op["responses"]["200"]["content"]) == {
        "application/xml", "application/json", "text/vnd.graphviz"}
    enums = [p["schema"]["enum"] for p in op["parameters"] if p["name"] == "format"]
    assert enums == [["graphml", "json-graph", "dot"]]
