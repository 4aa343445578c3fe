"""One token's data never reaches another: ids are never reused, every write checks owner and revision in
the statement that writes, and caches and ETags are keyed by what a new tableau cannot share.

Against a real uvicorn on 127.0.0.1 that requires tokens (alice and bob; two solvers, so that one
token's solves wait while another's run), and against the store itself for the database's ids.
"""

from __future__ import annotations

import threading
from datetime import datetime, timezone

import pytest
from service_helpers import SESSION_SETTINGS, Server, bearer, make_token
from sqlalchemy import MetaData
from test_limits import ONE_VIEW, _wait_for

from bootmap import examples
from bootmap.service import store as stores

MORE = {"action": {"type": "turn", "angle_deg": -90}, "steps": [{"view": "V1"}]}


@pytest.fixture(scope="module")
def two_solvers(tmp_path_factory, server_axioms):
    s = Server(tmp_path_factory.mktemp("isolation"), axioms=server_axioms, require_tokens=True,
               **{**SESSION_SETTINGS, "max_concurrent_solves": 2, "max_queued_solves": 4})
    s.tokens = {name: bearer(make_token(name, data_dir=s.data_dir)) for name in ("alice", "bob")}
    s.start()
    yield s
    s.stop()


def images_tableau(views: list[str], seed: int) -> dict:
    """The paper's world with an image at every step: each view its own 20-value image."""
    doc = examples.notched_rectangle(circuits=2).to_dict()
    names = {v: name for v, name in zip(("V0", "V1", "V2", "V3"), views)}
    for step in doc["steps"]:
        k = int(step["view"][1])
        step["image"] = [float(seed + k)] * 20
        step["view"] = names[step["view"]]
    return doc


def test_an_append_that_outlives_its_tableau_never_lands_on_the_next_one(two_solvers):
    """Alice appends to T while her other solve holds her one running place; meanwhile she deletes T and
    bob posts a tableau. Bob's is never T (SQLite used to give a deleted row's id to the next one), and
    alice's append, solved after, answers 404 instead of writing her steps into bob's tableau."""
    alice, bob = two_solvers.tokens["alice"], two_solvers.tokens["bob"]
    small = examples.notched_rectangle(circuits=2).to_dict()
    with two_solvers.client() as c:
        t = c.post("/tableaux", json=small, headers=alice).json()["id"]
        hard = threading.Thread(target=lambda: c.post("/tableaux", json=ONE_VIEW, headers=alice))
        hard.start()
        _wait_for(lambda: c.get("/health").json()["solves_running"] == 1)
        appended: list = []
        append = threading.Thread(target=lambda: appended.append(
            c.post(f"/tableaux/{t}/steps", json=MORE, headers=alice)))
        append.start()
        _wait_for(lambda: c.get("/health").json()["solves_waiting"] == 1)  # held: alice's place is taken
        assert c.delete(f"/tableaux/{t}", headers=alice).status_code == 204
        posted = c.post("/tableaux", json=small, headers=bob)  # runs on the other solver at once
        assert posted.status_code == 201, posted.text
        bobs = posted.json()["id"]
        hard.join()
        append.join()
        assert bobs != t
        assert appended[0].status_code == 404, appended[0].text
        assert c.get(f"/tableaux/{bobs}", headers=bob).json()["steps"] == len(small["steps"])


def test_a_recogniser_and_an_etag_are_never_those_of_a_deleted_tableau(two_solvers):
    alice, bob = two_solvers.tokens["alice"], two_solvers.tokens["bob"]
    with two_solvers.client() as c:
        doc = images_tableau(["ALICE_SECRET_V0", "ALICE_SECRET_V1", "ALICE_SECRET_V2", "ALICE_SECRET_V3"], seed=0)
        t = c.post("/tableaux", json=doc, headers=alice).json()["id"]
        seen = c.post(f"/tableaux/{t}/recognise", json={"image": [1.0] * 20}, headers=alice).json()
        assert seen["view"] == "ALICE_SECRET_V1" and seen["distance"] == 0.0
        etag = c.get(f"/tableaux/{t}/layout", headers=alice).headers["etag"]
        assert c.delete(f"/tableaux/{t}", headers=alice).status_code == 204

        bobs = c.post("/tableaux", json=images_tableau(["B0", "B1", "B2", "B3"], seed=0), headers=bob).json()["id"]
        mine = c.post(f"/tableaux/{bobs}/recognise", json={"image": [1.0] * 20}, headers=bob).json()
        assert mine["view"] == "B1"
        layout = c.get(f"/tableaux/{bobs}/layout", headers={**bob, "If-None-Match": etag})
        assert layout.status_code == 200 and layout.headers["etag"] != etag
        assert {d["view"] for d in layout.json()["map"]["dstates"].values()} == {"B0", "B1", "B2", "B3"}


def _old_schema(url: str) -> None:
    """A database as the service made it before its ids were AUTOINCREMENT (SQLite then reuses ids)."""
    md = MetaData()
    for t in stores.Base.metadata.sorted_tables:
        t.to_metadata(md).dialect_options["sqlite"]["autoincrement"] = False
    engine = stores.make_engine(url)
    md.create_all(engine)
    now = datetime.now(timezone.utc)
    with engine.begin() as conn:
        conn.execute(md.tables["tokens"].insert().values(id=1, name="alice", digest="d" * 64, admin=False,
                                                         created_at=now))
        for tid in (1, 2):
            conn.execute(md.tables["tableaux"].insert().values(id=tid, owner_id=1, revision=1, n_steps=1,
                                                               document="{}", created_at=now, updated_at=now))
            conn.execute(md.tables["maps"].insert().values(tableau_id=tid, revision=1, theory="x", dstates=1,
                                                           places=1, paths=1, document="{}", text=""))
    engine.dispose()


@pytest.mark.parametrize("older", [False, True], ids=["new database", "upgraded database"])
def test_ids_are_never_reused_and_writes_check_the_owner(tmp_path, older):
    url = f"sqlite:///{tmp_path / 'bootmap.sqlite3'}"
    if older:
        _old_schema(url)
    store = stores.Store(url)
    cmap = stores.MapRecord(1, "x", 1, 1, 1, "{}", "")
    owner = store.add_token("bob", "e" * 64, admin=False).id
    ids = [store.add("{}", 1, None, cmap, owner).id for _ in range(2)]
    store.delete(ids[-1])
    again = store.add("{}", 1, None, cmap, owner).id
    assert again > ids[-1], "a deleted tableau's id was given to a new one"
    if older:
        assert store.get(1).owner_id == 1 and store.get_map(2).revision == 1  # rows kept by the upgrade
        with pytest.raises(stores.NotOwner):  # tableau 1 is the old token's
            store.replace(1, '{"x": 1}', 1, None, stores.MapRecord(2, "x", 1, 1, 1, "{}", ""), owner=owner)
        with pytest.raises(stores.NotOwner):
            store.delete(1, owner=owner)
        assert store.get(1).revision == 1
    with pytest.raises(stores.NotFound):
        store.replace(ids[-1], "{}", 1, None, stores.MapRecord(2, "x", 1, 1, 1, "{}", ""), owner=owner)
    store.set_public(again, True, owner=owner)
    assert store.head(again).public
    store.close()
