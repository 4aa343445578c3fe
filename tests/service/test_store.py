"""The store: SQLite in WAL mode with a busy timeout, so concurrent writers wait instead of failing; an
append racing another is refused, not lost."""

import threading

import pytest
from sqlalchemy import text

from bootmap.service.store import Conflict, MapRecord, NotFound, Store


def a_map(revision: int) -> MapRecord:
    return MapRecord(revision, "theory", 8, 4, 4, '{"summary": {}}', "8 dstates")


def test_sqlite_runs_in_wal_mode_with_a_busy_timeout(tmp_path):
    store = Store(f"sqlite:///{tmp_path / 'db.sqlite3'}")
    with store.engine.connect() as conn:
        assert conn.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert conn.execute(text("PRAGMA busy_timeout")).scalar() >= 1000
    store.close()


def test_concurrent_writers_through_two_engines_all_succeed(tmp_path):
    url = f"sqlite:///{tmp_path / 'db.sqlite3'}"
    stores = [Store(url), Store(url)]  # two engines on one file, as two server processes would be
    errors = []

    def write(store):
        try:
            for _ in range(25):
                store.add('{"steps": []}', 1, None, a_map(1))
        except Exception as e:  # collect, so the assertion below shows what failed
            errors.append(e)

    threads = [threading.Thread(target=write, args=(stores[i % 2],)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == [] and stores[0].list(1000, 0)[0] == 200
    for s in stores:
        s.close()


def test_a_stale_revision_is_a_conflict_and_an_unknown_id_not_found(tmp_path):
    store = Store(f"sqlite:///{tmp_path / 'db.sqlite3'}")
    record = store.add('{"steps": [1]}', 1, None, a_map(1))
    store.replace(record.id, '{"steps": [1, 2]}', 2, None, a_map(2))
    with pytest.raises(Conflict):
        store.replace(record.id, '{"steps": [1, 3]}', 2, None, a_map(2))  # also built on revision 1
    assert store.get(record.id).document == '{"steps": [1, 2]}' and store.get_map(record.id).revision == 2
    with pytest.raises(NotFound):
        store.get(record.id + 1)
    with pytest.raises(NotFound):
        store.replace(record.id + 1, "{}", 1, None, a_map(2))
    store.close()
