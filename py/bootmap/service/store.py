"""Where the service keeps tableaux and their maps: SQLAlchemy 2, SQLite by default, any SQLAlchemy URL.

A tableau row holds the document as accepted (JSON text) and a revision that every append raises; its
map row holds the map's JSON, exactly as the API serves it, and its text table. Documents are stored as
text because they are only ever read whole: the service never queries inside them.

SQLite runs in WAL mode with a busy timeout, set on every new connection, so readers never block the
writer and concurrent writers wait for each other instead of failing with "database is locked".
"""

from __future__ import annotations

import functools
import itertools
import tempfile
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from pathlib import Path
from typing import Callable, Iterator

from sqlalchemy import (
    BigInteger,
    MetaData,
    Boolean,
    DateTime,
    ForeignKey,
    Integer,
    String,
    Text,
    create_engine,
    delete,
    event,
    func,
    inspect,
    or_,
    select,
    text,
    update,
)
from sqlalchemy.engine import Engine
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, sessionmaker

from ..errors import BootmapError

SQLITE_BUSY_TIMEOUT_S = 10.0  # the default of Settings.sqlite_busy_timeout_s


class NotFound(BootmapError):
    """No tableau has this id (or no token this name)."""

    def __init__(self, tableau_id: int, message: str | None = None):
        self.tableau_id = tableau_id
        super().__init__(message or f"no tableau has id {tableau_id}")


class Conflict(BootmapError):
    """The tableau changed (another append) between reading it and writing the new revision."""


class NotOwner(BootmapError):
    """The tableau exists, but the caller's token does not own it (checked in the statement that writes)."""

    def __init__(self, tableau_id: int):
        self.tableau_id = tableau_id
        super().__init__(f"tableau {tableau_id} belongs to another token; only its owner or an admin may change it")


class QuotaExceeded(BootmapError):
    """A token is over one of its limits (solves at once, requests per minute, stored bytes)."""

    def __init__(self, message: str, retry_after_s: int):
        self.retry_after_s = retry_after_s
        super().__init__(message)




# ``owner`` of a write: the caller's token id, or ANY for an admin (or the local user without tokens).
ANY = None


class Base(DeclarativeBase):
    pass


class TokenRow(Base):
    """An API token: only its SHA-256 is kept (the token itself is shown once, when it is made)."""

    __tablename__ = "tokens"
    # Ids are never reused (SQLite would otherwise give a deleted row's id to the next one): a token id in
    # a lease, a count or a cache always means the same token.
    __table_args__ = {"sqlite_autoincrement": True}

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    name: Mapped[str] = mapped_column(String(100), unique=True)
    digest: Mapped[str] = mapped_column(String(64), unique=True)
    admin: Mapped[bool] = mapped_column(Boolean, default=False)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    # Written by every solve lease and stored-bytes check: the row lock that makes "count, then add" one
    # step for this token, across every server on the database.
    touched_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)


class ServerRow(Base):
    """A running server and its last heartbeat, written every second or so (service/quotas.py). Another
    server's solve leases and request counts count only while its heartbeat is fresh."""

    __tablename__ = "servers"

    id: Mapped[str] = mapped_column(String(32), primary_key=True)  # random at each start: never reused
    name: Mapped[str] = mapped_column(String(200))  # host and process id, for whoever reads the table
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    heartbeat_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), index=True)


class SolveLease(Base):
    """A solve a token has running or waiting on a server; it counts while that server's heartbeat is fresh.
    (No foreign key to ``servers``: a server forgotten while it stalled writes its row again.)"""

    __tablename__ = "solve_leases"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    token_id: Mapped[int] = mapped_column(ForeignKey("tokens.id", ondelete="CASCADE"), index=True)
    server_id: Mapped[str] = mapped_column(String(32), index=True)
    started_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))


class RequestCount(Base):
    """One server's recent requests of one token, as that server last wrote them: ``counts`` is its own
    text (service/quotas.py: how many requests in each second of the last minute)."""

    __tablename__ = "request_counts"

    server_id: Mapped[str] = mapped_column(String(32), primary_key=True)
    token_id: Mapped[int] = mapped_column(ForeignKey("tokens.id", ondelete="CASCADE"), primary_key=True)
    counts: Mapped[str] = mapped_column(Text)


class TableauRow(Base):
    __tablename__ = "tableaux"
    # Ids are never reused: a request that read tableau N (its owner, its revision) and writes later can
    # only ever meet that tableau, or none; a cache keyed by the id never serves a newer tableau.
    __table_args__ = {"sqlite_autoincrement": True}

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    owner_id: Mapped[int | None] = mapped_column(ForeignKey("tokens.id", ondelete="SET NULL"), nullable=True,
                                                 index=True)
    public: Mapped[bool] = mapped_column(Boolean, default=False, server_default=text("false"))
    stored_bytes: Mapped[int] = mapped_column(BigInteger, default=0, server_default=text("0"))
    revision: Mapped[int] = mapped_column(Integer)
    n_steps: Mapped[int] = mapped_column(Integer)
    views_k: Mapped[int | None] = mapped_column(Integer, nullable=True)
    document: Mapped[str] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))


class MapRow(Base):
    __tablename__ = "maps"

    tableau_id: Mapped[int] = mapped_column(ForeignKey("tableaux.id", ondelete="CASCADE"), primary_key=True)
    revision: Mapped[int] = mapped_column(Integer)
    theory: Mapped[str] = mapped_column(String(64))
    dstates: Mapped[int] = mapped_column(Integer)
    places: Mapped[int] = mapped_column(Integer)
    paths: Mapped[int] = mapped_column(Integer)
    document: Mapped[str] = mapped_column(Text)
    text: Mapped[str] = mapped_column(Text)


class AssertionRow(Base):
    """A person's assertion about a tableau's map (bootmap.mapping.assertions): two time points are one
    dstate (``same``) or not (``apart``), hard or at a cost; who made it (the token's name) and when."""

    __tablename__ = "assertions"
    __table_args__ = {"sqlite_autoincrement": True}

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    tableau_id: Mapped[int] = mapped_column(ForeignKey("tableaux.id", ondelete="CASCADE"), index=True)
    kind: Mapped[str] = mapped_column(String(8))
    a: Mapped[int] = mapped_column(Integer)
    b: Mapped[int] = mapped_column(Integer)
    soft: Mapped[bool] = mapped_column(Boolean, default=False)
    cost: Mapped[int] = mapped_column(Integer)
    note: Mapped[str | None] = mapped_column(Text, nullable=True)
    made_by: Mapped[str] = mapped_column(String(100))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))


@dataclass(frozen=True)
class AssertionRecord:
    id: int
    tableau_id: int
    kind: str
    a: int
    b: int
    soft: bool
    cost: int
    note: str | None
    made_by: str
    created_at: datetime

    @property
    def entry(self) -> dict:
        """The assertion as a solver reads it (a bootmap.assertions/1 entry of time points)."""
        return {self.kind: [self.a, self.b], "soft": self.soft, **({"cost": self.cost} if self.soft else {})}


@dataclass(frozen=True)
class MapRecord:
    """A solved map, ready to serve: ``document`` is the JSON the API returns."""

    revision: int
    theory: str
    dstates: int
    places: int
    paths: int
    document: str
    text: str


@dataclass(frozen=True)
class TableauRecord:
    id: int
    revision: int
    n_steps: int
    views_k: int | None
    document: str
    created_at: datetime
    updated_at: datetime
    owner_id: int | None = None
    public: bool = False

    @property
    def key(self) -> str:
        """What tells this tableau's revision apart from every other tableau's, for caches and ETags: the
        id (never reused), the creation time and the revision."""
        return f"{self.id}.{int(self.created_at.timestamp() * 1e6)}.r{self.revision}"


@dataclass(frozen=True)
class TableauSummary:
    id: int
    revision: int
    n_steps: int
    dstates: int
    places: int
    paths: int
    updated_at: datetime


@dataclass(frozen=True)
class TokenRecord:
    id: int
    name: str
    admin: bool


@dataclass(frozen=True)
class TokenListing:
    """A token as ``bootmap token list`` shows it: its name, whether it is an admin's, when it was made,
    and how many tableaux it owns."""

    name: str
    admin: bool
    created_at: datetime
    tableaux: int


@dataclass(frozen=True)
class HeldLease:
    """A solve place a token holds: when it was taken, and the last heartbeat of the server holding it
    (None when it is the asking server's own)."""

    started_at: datetime
    heartbeat_at: datetime | None


class SolvePlacesTaken(BootmapError):
    """Every solve place of a token is held (:meth:`Store.lease_solve`); ``held`` says by what."""

    def __init__(self, held: list[HeldLease]):
        self.held = held
        super().__init__(f"the token holds {len(held)} solve places")


def _utc(t: datetime) -> datetime:
    # SQLite returns naive datetimes; every one stored here is UTC.
    return t if t.tzinfo else t.replace(tzinfo=timezone.utc)


def _record(row: TableauRow) -> TableauRecord:
    return TableauRecord(row.id, row.revision, row.n_steps, row.views_k, row.document, _utc(row.created_at),
                         _utc(row.updated_at), row.owner_id, bool(row.public))


def make_engine(url: str, busy_timeout_s: float = SQLITE_BUSY_TIMEOUT_S) -> Engine:
    """An engine for ``url``; for SQLite, the file's directory is created, WAL is switched on, and a writer
    waits up to ``busy_timeout_s`` for another connection's write lock."""
    if url.startswith("sqlite:///"):
        path = url.removeprefix("sqlite:///")
        if path and path != ":memory:":
            Path(path).parent.mkdir(parents=True, exist_ok=True)
    # Streamed reads hold a connection while the client reads: room for as many as the thread pool runs.
    engine = create_engine(url, pool_pre_ping=not url.startswith("sqlite"), pool_size=10, max_overflow=30)
    if engine.dialect.name == "sqlite":
        event.listen(engine, "connect",
                     functools.partial(_sqlite_pragmas, busy_timeout_ms=int(busy_timeout_s * 1000)))
    return engine


def _never_reuse_ids(engine: Engine, table) -> None:
    """Give an SQLite table made before its ids were AUTOINCREMENT that property: SQLite cannot alter a
    table so, so it is rebuilt (a new table, the rows copied, the old one dropped), in one transaction
    with foreign keys off so that the rows that reference it stay as they are."""
    with engine.connect() as conn:
        made = conn.exec_driver_sql("SELECT sql FROM sqlite_master WHERE type = 'table' AND name = ?",
                                    (table.name,)).scalar() or ""
        conn.rollback()
        if "AUTOINCREMENT" in made.upper():
            return
        conn.exec_driver_sql("PRAGMA foreign_keys=OFF")  # not inside a transaction: SQLite ignores it there
        conn.commit()
        try:
            with conn.begin():
                scratch = MetaData()
                for t in Base.metadata.sorted_tables:  # what its foreign keys name must be in the same metadata
                    t.to_metadata(scratch)
                new = table.to_metadata(scratch, name=f"{table.name}_rebuilt")
                new.indexes.clear()  # made again below, under their own names, once the table has its name
                new.create(conn)
                columns = ", ".join(f'"{c.name}"' for c in table.columns)
                conn.exec_driver_sql(f'INSERT INTO "{new.name}" ({columns}) SELECT {columns} FROM "{table.name}"')
                conn.exec_driver_sql(f'DROP TABLE "{table.name}"')  # and its indexes
                conn.exec_driver_sql(f'ALTER TABLE "{new.name}" RENAME TO "{table.name}"')
                for index in table.indexes:
                    index.create(conn)
        finally:
            conn.exec_driver_sql("PRAGMA foreign_keys=ON")
            conn.commit()


def _sqlite_pragmas(dbapi_connection, _record, busy_timeout_ms: int) -> None:
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute(f"PRAGMA busy_timeout={int(busy_timeout_ms)}")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.close()


# Columns added since the first release: added to an older database when it is opened.
_NEW_COLUMNS = {"owner_id": "INTEGER REFERENCES tokens(id) ON DELETE SET NULL",
                "public": "BOOLEAN NOT NULL DEFAULT false", "stored_bytes": "BIGINT NOT NULL DEFAULT 0"}
STREAM_CHUNK = 2**18  # characters per chunk of a streamed read (documents are ASCII JSON)


class Store:
    """The repository: every method is one short transaction and returns plain records."""

    def __init__(self, url: str, busy_timeout_s: float = SQLITE_BUSY_TIMEOUT_S):
        self.busy_timeout_s = busy_timeout_s  # (SQLite: how long a writer waits for the write lock)
        self.engine = make_engine(url, busy_timeout_s)
        self._renew_server_tables()
        Base.metadata.create_all(self.engine)
        self._upgrade()
        self._session = sessionmaker(self.engine, expire_on_commit=False)

    def _upgrade(self) -> None:
        have = {c["name"] for c in inspect(self.engine).get_columns("tableaux")}
        with self.engine.begin() as conn:
            for name, ddl in _NEW_COLUMNS.items():
                if name not in have:
                    conn.execute(text(f"ALTER TABLE tableaux ADD COLUMN {name} {ddl}"))
        if self.engine.dialect.name == "sqlite":
            for table in (TokenRow.__table__, TableauRow.__table__):
                _never_reuse_ids(self.engine, table)

    def _renew_server_tables(self) -> None:
        """An older database's ``solve_leases`` and ``request_counts`` (before servers had heartbeats) are
        dropped, to be made afresh: they only ever hold what running servers are doing."""
        tables = inspect(self.engine).get_table_names()
        with self.engine.begin() as conn:
            for table in (SolveLease.__tablename__, RequestCount.__tablename__):
                if table in tables and "server_id" not in {c["name"] for c in inspect(conn).get_columns(table)}:
                    conn.execute(text(f"DROP TABLE {table}"))

    def close(self) -> None:
        self.engine.dispose()

    def ping(self) -> None:
        with self.engine.connect() as conn:
            conn.execute(text("SELECT 1"))

    # --- Tableaux and maps ---------------------------------------------------------------------------

    def add(self, document: str, n_steps: int, views_k: int | None, cmap: MapRecord, owner_id: int | None = None,
            max_bytes: int | None = None, public: bool = False) -> TableauRecord:
        """Store a new tableau (revision 1) with its map; over the owner's ``max_bytes``, QuotaExceeded."""
        now = datetime.now(timezone.utc)
        size = _size(document, cmap)
        row = TableauRow(revision=1, n_steps=n_steps, views_k=views_k, document=document, created_at=now,
                         updated_at=now, owner_id=owner_id, public=public, stored_bytes=size)
        with self._session.begin() as s:
            if owner_id is not None and max_bytes is not None:
                _check_bytes(s, owner_id, size, max_bytes)
            s.add(row)
            s.flush()  # assigns the id
            s.add(_map_row(row.id, cmap))
        return _record(row)

    def get(self, tableau_id: int) -> TableauRecord:
        with self._session() as s:
            row = s.get(TableauRow, tableau_id)
            if row is None:
                raise NotFound(tableau_id)
            return _record(row)

    def head(self, tableau_id: int) -> TableauRecord:
        """The tableau's record without its document (``document`` is empty): who owns it, its revision."""
        with self._session() as s:
            row = s.execute(select(*_HEAD).where(TableauRow.id == tableau_id)).first()
        if row is None:
            raise NotFound(tableau_id)
        return _head_record(row)

    def get_map(self, tableau_id: int) -> MapRecord:
        with self._session() as s:
            row = s.get(MapRow, tableau_id)
            if row is None:
                raise NotFound(tableau_id)
            return MapRecord(row.revision, row.theory, row.dstates, row.places, row.paths, row.document, row.text)

    def map_head(self, tableau_id: int) -> tuple[int, str]:
        """The revision and theory id of the tableau's stored map, without its document."""
        with self._session() as s:
            row = s.execute(select(MapRow.revision, MapRow.theory).where(MapRow.tableau_id == tableau_id)).first()
        if row is None:
            raise NotFound(tableau_id)
        return row[0], row[1]

    def replace(self, tableau_id: int, document: str, n_steps: int, views_k: int | None,
                cmap: MapRecord, owner: int | None = ANY, max_bytes: int | None = None) -> TableauRecord:
        """Store revision ``cmap.revision`` of the tableau and its map, unless another request stored that
        revision first (:class:`Conflict`), the tableau is gone (:class:`NotFound`), ``owner`` (a token
        id; ANY for an admin) no longer owns it (:class:`NotOwner`) or the owner would go over
        ``max_bytes`` (QuotaExceeded)."""
        now = datetime.now(timezone.utc)
        revision, expected_revision = cmap.revision, cmap.revision - 1
        size = _size(document, cmap)
        with self._session.begin() as s:
            # Write first, read nothing before: the row lock is taken by this UPDATE, so two appends
            # cannot both pass the revision check, and the owner is checked by the statement that writes.
            done = s.execute(update(TableauRow)
                             .where(TableauRow.id == tableau_id, TableauRow.revision == expected_revision,
                                    *_owned_by(owner))
                             .values(revision=revision, n_steps=n_steps, views_k=views_k, document=document,
                                     updated_at=now, stored_bytes=size))
            if done.rowcount != 1:
                _why_not_written(s, tableau_id, owner)
                raise Conflict(f"tableau {tableau_id} changed while this request was solved "
                               f"(it is no longer at revision {expected_revision}); send the request again")
            stored_owner = s.scalar(select(TableauRow.owner_id).where(TableauRow.id == tableau_id))
            if stored_owner is not None and max_bytes is not None:
                _check_bytes(s, stored_owner, 0, max_bytes)  # this revision is counted already
            s.merge(_map_row(tableau_id, cmap))
            row = s.get(TableauRow, tableau_id)
            return _record(row)

    def set_public(self, tableau_id: int, public: bool, owner: int | None = ANY) -> None:
        """Make the tableau public or private, if ``owner`` (a token id; ANY for an admin) owns it."""
        with self._session.begin() as s:
            done = s.execute(update(TableauRow).where(TableauRow.id == tableau_id, *_owned_by(owner))
                             .values(public=public))
            if done.rowcount != 1:
                _why_not_written(s, tableau_id, owner)

    def delete(self, tableau_id: int, owner: int | None = ANY) -> None:
        """Delete the tableau, its map and its assertions, if ``owner`` (a token id; ANY for an admin) owns it."""
        with self._session.begin() as s:
            done = s.execute(delete(TableauRow).where(TableauRow.id == tableau_id, *_owned_by(owner)))
            if done.rowcount != 1:
                _why_not_written(s, tableau_id, owner)
            s.execute(delete(MapRow).where(MapRow.tableau_id == tableau_id))
            s.execute(delete(AssertionRow).where(AssertionRow.tableau_id == tableau_id))

    # --- A person's assertions -----------------------------------------------------------------------

    def assertions(self, tableau_id: int) -> list[AssertionRecord]:
        """The tableau's assertions, oldest first."""
        with self._session() as s:
            rows = s.scalars(select(AssertionRow).where(AssertionRow.tableau_id == tableau_id)
                             .order_by(AssertionRow.id)).all()
        return [_assertion_record(r) for r in rows]

    def add_assertion(self, tableau_id: int, kind: str, a: int, b: int, soft: bool, cost: int, note: str | None,
                      made_by: str, cmap: MapRecord, owner: int | None = ANY) -> AssertionRecord:
        """Keep a new assertion and the map solved with it and the tableau's other assertions, as revision
        ``cmap.revision`` (an assertion changes the map as an append does), unless another request stored
        that revision first (:class:`Conflict`), the tableau is gone (:class:`NotFound`) or ``owner`` no
        longer owns it (:class:`NotOwner`)."""
        now = datetime.now(timezone.utc)
        with self._session.begin() as s:
            _next_revision(s, tableau_id, cmap.revision, owner, now)
            row = AssertionRow(tableau_id=tableau_id, kind=kind, a=a, b=b, soft=soft, cost=cost, note=note,
                               made_by=made_by, created_at=now)
            s.add(row)
            s.merge(_map_row(tableau_id, cmap))
            s.flush()
            return _assertion_record(row)

    def delete_assertion(self, tableau_id: int, assertion_id: int, cmap: MapRecord, owner: int | None = ANY) -> None:
        """Remove an assertion and keep the map solved without it as revision ``cmap.revision``, on the
        same terms as :meth:`add_assertion`."""
        with self._session.begin() as s:
            _next_revision(s, tableau_id, cmap.revision, owner, datetime.now(timezone.utc))
            done = s.execute(delete(AssertionRow).where(AssertionRow.id == assertion_id,
                                                        AssertionRow.tableau_id == tableau_id))
            if done.rowcount != 1:
                raise NotFound(0, f"tableau {tableau_id} has no assertion {assertion_id}")
            s.merge(_map_row(tableau_id, cmap))

    def list(self, limit: int, offset: int, owner_id: int | None = None,
             everyone: bool = True) -> tuple[int, list[TableauSummary]]:
        """Stored tableaux: all of them (``everyone``), else those of ``owner_id`` and the public ones."""
        visible = True if everyone else or_(TableauRow.owner_id == owner_id, TableauRow.public.is_(True))
        with self._session() as s:
            total = s.scalar(select(func.count()).select_from(TableauRow).where(visible)) or 0
            rows = s.execute(select(TableauRow.id, TableauRow.revision, TableauRow.n_steps, MapRow.dstates,
                                    MapRow.places, MapRow.paths, TableauRow.updated_at)
                             .join(MapRow, MapRow.tableau_id == TableauRow.id).where(visible)
                             .order_by(TableauRow.id).limit(limit).offset(offset)).all()
        return total, [TableauSummary(*r[:6], _utc(r[6])) for r in rows]

    def stream(self, tableau_id: int, what: str, allowed: Callable[[TableauRecord], None] | None = None) -> "Stream":
        """A stored text (``tableau``, ``map`` or ``text``), read in chunks of STREAM_CHUNK from one
        snapshot: the server never holds a whole large document for a read. ``allowed(head)`` raises if the
        text may not be read, before any of it is copied. Close it when done."""
        return Stream(self.engine, tableau_id, what, allowed)

    # --- Tokens and quotas ---------------------------------------------------------------------------

    def add_token(self, name: str, digest: str, admin: bool) -> TokenRecord:
        row = TokenRow(name=name, digest=digest, admin=admin, created_at=datetime.now(timezone.utc))
        with self._session.begin() as s:
            if s.scalar(select(TokenRow.id).where(TokenRow.name == name)) is not None:
                raise Conflict(f"a token named {name!r} exists already")
            s.add(row)
        return TokenRecord(row.id, row.name, row.admin)

    def delete_token(self, name: str) -> None:
        """Revoke a token: it is refused from now on, on every server; its tableaux stay, owned by no one
        (admins reach them)."""
        with self._session.begin() as s:
            token_id = s.scalar(select(TokenRow.id).where(TokenRow.name == name))
            if token_id is None:
                raise NotFound(0, f"no token is named {name!r}")
            s.execute(update(TableauRow).where(TableauRow.owner_id == token_id).values(owner_id=None))
            s.execute(delete(SolveLease).where(SolveLease.token_id == token_id))
            s.execute(delete(RequestCount).where(RequestCount.token_id == token_id))
            s.execute(delete(TokenRow).where(TokenRow.id == token_id))

    def tokens(self) -> list[TokenListing]:
        """Every token (never its hash), oldest first, with how many tableaux it owns."""
        owned = (select(TableauRow.owner_id, func.count().label("n")).group_by(TableauRow.owner_id).subquery())
        with self._session() as s:
            rows = s.execute(select(TokenRow.name, TokenRow.admin, TokenRow.created_at, owned.c.n)
                             .outerjoin(owned, owned.c.owner_id == TokenRow.id).order_by(TokenRow.id)).all()
        return [TokenListing(name, bool(admin), _utc(created), int(n or 0)) for name, admin, created, n in rows]

    def token_by_digest(self, digest: str) -> TokenRecord | None:
        with self._session() as s:
            row = s.execute(select(TokenRow.id, TokenRow.name, TokenRow.admin).where(TokenRow.digest == digest)).first()
        return None if row is None else TokenRecord(row[0], row[1], bool(row[2]))

    # --- Servers: heartbeats, request counts, solve leases ---------------------------------------------

    def heartbeat(self, server_id: str, name: str, counts: dict[int, str | None], stale_s: float,
                  forget_s: float) -> dict[int, list[str]]:
        """Write this server's heartbeat and its request counts that changed (token id -> text, None when
        the token has none left); forget the servers silent for ``forget_s``, with their leases and counts;
        return the counts of the other servers heard from within ``stale_s`` (token id -> their texts)."""
        now = datetime.now(timezone.utc)
        with self._session.begin() as s:
            # A write first: SQLite takes its write lock here (waiting for it), not halfway through.
            if s.execute(update(ServerRow).where(ServerRow.id == server_id)
                         .values(heartbeat_at=now)).rowcount == 0:
                s.add(ServerRow(id=server_id, name=name[:200], started_at=now, heartbeat_at=now))
            if counts:
                s.execute(delete(RequestCount).where(RequestCount.server_id == server_id,
                                                     RequestCount.token_id.in_(counts)))
                kept = [t for t, c in counts.items() if c is not None]
                known = set(s.scalars(select(TokenRow.id).where(TokenRow.id.in_(kept)))) if kept else set()
                s.add_all(RequestCount(server_id=server_id, token_id=t, counts=counts[t]) for t in kept if t in known)
            silent = now - timedelta(seconds=forget_s)
            gone = list(s.scalars(select(ServerRow.id).where(ServerRow.heartbeat_at < silent,
                                                            ServerRow.id != server_id)))
            if gone:
                _remove_servers(s, gone)
            rows = s.execute(select(RequestCount.token_id, RequestCount.counts)
                             .join(ServerRow, ServerRow.id == RequestCount.server_id)
                             .where(RequestCount.server_id != server_id,
                                    ServerRow.heartbeat_at >= now - timedelta(seconds=stale_s))).all()
        elsewhere: dict[int, list[str]] = {}
        for token_id, text_ in rows:
            elsewhere.setdefault(token_id, []).append(text_)
        return elsewhere

    def remove_server(self, server_id: str) -> None:
        """A server that stops: its row, its solve leases and its request counts go."""
        with self._session.begin() as s:
            _remove_servers(s, [server_id])

    def lease_solve(self, token_id: int, limit: int, server_id: str, stale_s: float) -> int:
        """Take one of the token's ``limit`` solve places (on any server) for this server. Another server's
        lease counts only while that server's heartbeat is under ``stale_s`` old: a dead server's places
        free by themselves. None free: :class:`SolvePlacesTaken`."""
        now = datetime.now(timezone.utc)
        with self._session.begin() as s:
            _lock_token(s, token_id)
            rows = s.execute(select(SolveLease.started_at, SolveLease.server_id, ServerRow.heartbeat_at)
                             .join(ServerRow, ServerRow.id == SolveLease.server_id, isouter=True)
                             .where(SolveLease.token_id == token_id)).all()
            fresh = now - timedelta(seconds=stale_s)
            held = [HeldLease(_utc(started), None if server == server_id else _utc(beat))
                    for started, server, beat in rows
                    if server == server_id or (beat is not None and _utc(beat) >= fresh)]
            if len(held) >= limit:
                raise SolvePlacesTaken(held)
            lease = SolveLease(token_id=token_id, server_id=server_id, started_at=now)
            s.add(lease)
            s.flush()
            return lease.id

    def release_solve(self, lease_id: int) -> None:
        with self._session.begin() as s:
            s.execute(delete(SolveLease).where(SolveLease.id == lease_id))


@functools.lru_cache(maxsize=4)
def store_at(url: str) -> Store:
    """This process's Store of the database at ``url``, opened once: the intake and solver processes
    read and write stored tableaux themselves."""
    return Store(url)


_HEAD = (TableauRow.id, TableauRow.revision, TableauRow.n_steps, TableauRow.views_k, TableauRow.created_at,
         TableauRow.updated_at, TableauRow.owner_id, TableauRow.public)


def _head_record(row) -> TableauRecord:
    return TableauRecord(row[0], row[1], row[2], row[3], "", _utc(row[4]), _utc(row[5]), row[6], bool(row[7]))


def _owned_by(owner: int | None) -> tuple:
    """The WHERE clause that limits a write to the owner's tableaux (none for ANY)."""
    return () if owner is ANY else (TableauRow.owner_id == owner,)


def _why_not_written(s, tableau_id: int, owner: int | None) -> None:
    """After a write matched no row: NotFound if the tableau is gone, NotOwner if it is another's."""
    stored_owner = s.execute(select(TableauRow.owner_id).where(TableauRow.id == tableau_id)).first()
    if stored_owner is None:
        raise NotFound(tableau_id)
    if owner is not ANY and stored_owner[0] != owner:
        raise NotOwner(tableau_id)


def _size(document: str, cmap: MapRecord) -> int:
    return len(document) + len(cmap.document) + len(cmap.text)


def _lock_token(s, token_id: int) -> None:
    """Take the token's row lock (a write: SQLite's write lock, PostgreSQL's row lock) so that what
    follows in the transaction is one step for this token on every server."""
    s.execute(update(TokenRow).where(TokenRow.id == token_id).values(touched_at=datetime.now(timezone.utc)))


def _remove_servers(s, server_ids: list[str]) -> None:
    s.execute(delete(SolveLease).where(SolveLease.server_id.in_(server_ids)))
    s.execute(delete(RequestCount).where(RequestCount.server_id.in_(server_ids)))
    s.execute(delete(ServerRow).where(ServerRow.id.in_(server_ids)))


def _check_bytes(s, owner_id: int, adding: int, max_bytes: int) -> None:
    _lock_token(s, owner_id)
    stored = s.scalar(select(func.coalesce(func.sum(TableauRow.stored_bytes), 0))
                      .where(TableauRow.owner_id == owner_id)) or 0
    if stored + adding > max_bytes:
        raise QuotaExceeded(f"this token would keep {stored + adding} bytes stored, more than its limit of "
                            f"{max_bytes} (BOOTMAP_TOKEN_MAX_STORED_BYTES); delete tableaux to make room", 60)


class Stream:
    """One stored text, from one read snapshot, handed out in chunks.

    The text is copied from the database in chunks of STREAM_CHUNK (SQLite's incremental blob I/O,
    PostgreSQL's ``substr`` in a REPEATABLE READ transaction) into a temporary file, and the database
    connection goes back to the pool at once: a client that reads slowly, or not at all, holds a file,
    never a connection. A small text (most maps) is kept in memory as ``whole``. Close it when done."""

    _COLUMNS = {"tableau": (TableauRow, "document", "id"), "map": (MapRow, "document", "tableau_id"),
                "text": (MapRow, "text", "tableau_id")}

    def __init__(self, engine: Engine, tableau_id: int, what: str,
                 allowed: Callable[[TableauRecord], None] | None = None):
        self.whole: bytes | None = None
        self._file = None
        with engine.connect() as conn:
            if engine.dialect.name == "postgresql":
                conn = conn.execution_options(isolation_level="REPEATABLE READ")
            with conn.begin():
                self.head = _head_record_or_none(conn, tableau_id)
                if self.head is None:
                    raise NotFound(tableau_id)
                if allowed is not None:
                    allowed(self.head)
                chunks = _chunks(conn, *self._COLUMNS[what], tableau_id)
                first = next(chunks, b"")
                following = next(chunks, None)
                if following is None:  # small: read at once
                    self.whole = first
                    return
                self._file = tempfile.TemporaryFile(prefix="bootmap-read-")
                try:
                    for chunk in itertools.chain((first, following), chunks):
                        self._file.write(chunk)
                    self._file.seek(0)
                except BaseException:
                    self.close()
                    raise

    def __iter__(self) -> Iterator[bytes]:
        if self.whole is not None:
            yield self.whole
            return
        try:
            while chunk := self._file.read(STREAM_CHUNK):
                yield chunk
        finally:
            self.close()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def _chunks(conn, table, column: str, key: str, tableau_id: int) -> Iterator[bytes]:
    """The stored text, STREAM_CHUNK at a time, within the connection's transaction."""
    c, where = table.__table__.c[column], getattr(table, key) == tableau_id
    if conn.dialect.name == "sqlite":  # incremental blob I/O: only the chunk asked for is read
        rowid = conn.scalar(select(text("rowid")).where(where))
        if rowid is None:
            raise NotFound(tableau_id)
        with conn.connection.dbapi_connection.blobopen(table.__tablename__, column, rowid, readonly=True) as blob:
            while chunk := blob.read(STREAM_CHUNK):
                yield chunk
        return
    length = conn.scalar(select(func.length(c)).where(where))
    if length is None:
        raise NotFound(tableau_id)
    for start in range(0, length, STREAM_CHUNK):
        yield conn.scalar(select(func.substr(c, start + 1, STREAM_CHUNK)).where(where)).encode()


def _head_record_or_none(conn, tableau_id: int) -> TableauRecord | None:
    row = conn.execute(select(*_HEAD).where(TableauRow.id == tableau_id)).first()
    return None if row is None else _head_record(row)


def _next_revision(s, tableau_id: int, revision: int, owner: int | None, now: datetime) -> None:
    """Move the tableau to ``revision`` from the one before it (taking its row lock), or say why not."""
    done = s.execute(update(TableauRow).where(TableauRow.id == tableau_id, TableauRow.revision == revision - 1,
                                              *_owned_by(owner)).values(revision=revision, updated_at=now))
    if done.rowcount != 1:
        _why_not_written(s, tableau_id, owner)
        raise Conflict(f"tableau {tableau_id} changed while this request was solved (it is no longer at "
                       f"revision {revision - 1}); send the request again")


def _assertion_record(row: AssertionRow) -> AssertionRecord:
    return AssertionRecord(row.id, row.tableau_id, row.kind, row.a, row.b, bool(row.soft), row.cost, row.note,
                           row.made_by, _utc(row.created_at))


def _map_row(tableau_id: int, m: MapRecord) -> MapRow:
    return MapRow(tableau_id=tableau_id, revision=m.revision, theory=m.theory, dstates=m.dstates, places=m.places,
                  paths=m.paths, document=m.document, text=m.text)
