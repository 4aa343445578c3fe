"""Where the service keeps tableaux and their maps: SQLAlchemy 2, SQLite by default, any SQLAlchemy URL.

A tableau row holds the document as accepted (JSON text) and a revision that every append raises; its
map row holds the map's JSON, exactly as the API serves it, and its text table. Documents are stored as
text because they are only ever read whole: the service never queries inside them.

SQLite runs in WAL mode with a busy timeout, set on every new connection, so readers never block the
writer and concurrent writers wait for each other instead of failing with "database is locked".
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from sqlalchemy import DateTime, ForeignKey, Integer, String, Text, create_engine, event, func, select, text, update
from sqlalchemy.engine import Engine
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, sessionmaker

from ..errors import BootmapError

SQLITE_BUSY_TIMEOUT_MS = 10_000


class NotFound(BootmapError):
    """No tableau has this id."""

    def __init__(self, tableau_id: int):
        self.tableau_id = tableau_id
        super().__init__(f"no tableau has id {tableau_id}")


class Conflict(BootmapError):
    """The tableau changed (another append) between reading it and writing the new revision."""


class Base(DeclarativeBase):
    pass


class TableauRow(Base):
    __tablename__ = "tableaux"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
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


@dataclass(frozen=True)
class TableauSummary:
    id: int
    revision: int
    n_steps: int
    dstates: int
    places: int
    paths: int
    updated_at: datetime


def _utc(t: datetime) -> datetime:
    # SQLite returns naive datetimes; every one stored here is UTC.
    return t if t.tzinfo else t.replace(tzinfo=timezone.utc)


def _record(row: TableauRow) -> TableauRecord:
    return TableauRecord(row.id, row.revision, row.n_steps, row.views_k, row.document, _utc(row.created_at),
                         _utc(row.updated_at))


def make_engine(url: str) -> Engine:
    """An engine for ``url``; for SQLite, the file's directory is created and WAL is switched on."""
    if url.startswith("sqlite:///"):
        path = url.removeprefix("sqlite:///")
        if path and path != ":memory:":
            Path(path).parent.mkdir(parents=True, exist_ok=True)
    engine = create_engine(url, pool_pre_ping=not url.startswith("sqlite"))
    if engine.dialect.name == "sqlite":
        event.listen(engine, "connect", _sqlite_pragmas)
    return engine


def _sqlite_pragmas(dbapi_connection, _record) -> None:
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute(f"PRAGMA busy_timeout={SQLITE_BUSY_TIMEOUT_MS}")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.close()


class Store:
    """The repository: every method is one short transaction and returns plain records."""

    def __init__(self, url: str):
        self.engine = make_engine(url)
        Base.metadata.create_all(self.engine)
        self._session = sessionmaker(self.engine, expire_on_commit=False)

    def close(self) -> None:
        self.engine.dispose()

    def ping(self) -> None:
        with self.engine.connect() as conn:
            conn.execute(text("SELECT 1"))

    def add(self, document: str, n_steps: int, views_k: int | None, cmap: MapRecord) -> TableauRecord:
        """Store a new tableau (revision 1) with its map."""
        now = datetime.now(timezone.utc)
        row = TableauRow(revision=1, n_steps=n_steps, views_k=views_k, document=document, created_at=now,
                         updated_at=now)
        with self._session.begin() as s:
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

    def get_map(self, tableau_id: int) -> MapRecord:
        with self._session() as s:
            row = s.get(MapRow, tableau_id)
            if row is None:
                raise NotFound(tableau_id)
            return MapRecord(row.revision, row.theory, row.dstates, row.places, row.paths, row.document, row.text)

    def replace(self, tableau_id: int, document: str, n_steps: int, views_k: int | None,
                cmap: MapRecord) -> TableauRecord:
        """Store revision ``cmap.revision`` of the tableau and its map, unless another request stored that
        revision first (:class:`Conflict`)."""
        now = datetime.now(timezone.utc)
        revision, expected_revision = cmap.revision, cmap.revision - 1
        with self._session.begin() as s:
            # Write first, read nothing before: the row lock is taken by this UPDATE, so two appends
            # cannot both pass the revision check.
            done = s.execute(update(TableauRow)
                             .where(TableauRow.id == tableau_id, TableauRow.revision == expected_revision)
                             .values(revision=revision, n_steps=n_steps, views_k=views_k, document=document,
                                     updated_at=now))
            if done.rowcount != 1:
                if s.get(TableauRow, tableau_id) is None:
                    raise NotFound(tableau_id)
                raise Conflict(f"tableau {tableau_id} changed while this request was solved "
                               f"(it is no longer at revision {expected_revision}); send the request again")
            s.merge(_map_row(tableau_id, cmap))
            row = s.get(TableauRow, tableau_id)
            return _record(row)

    def list(self, limit: int, offset: int) -> tuple[int, list[TableauSummary]]:
        with self._session() as s:
            total = s.scalar(select(func.count()).select_from(TableauRow)) or 0
            rows = s.execute(select(TableauRow.id, TableauRow.revision, TableauRow.n_steps, MapRow.dstates,
                                    MapRow.places, MapRow.paths, TableauRow.updated_at)
                             .join(MapRow, MapRow.tableau_id == TableauRow.id)
                             .order_by(TableauRow.id).limit(limit).offset(offset)).all()
        return total, [TableauSummary(*r[:6], _utc(r[6])) for r in rows]


def _map_row(tableau_id: int, m: MapRecord) -> MapRow:
    return MapRow(tableau_id=tableau_id, revision=m.revision, theory=m.theory, dstates=m.dstates, places=m.places,
                  paths=m.paths, document=m.document, text=m.text)
