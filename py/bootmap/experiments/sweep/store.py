"""A sweep's results on disk: one JSON line per finished cell, written the moment it finishes.

``DIR/results.jsonl`` is appended to as cells finish, so an interrupted sweep loses only the cells that
were running; ``--resume`` reads it back and runs the rest. When the sweep ends, the file is rewritten
in grid order with exactly the grid's cells, and ``DIR/results.csv`` holds the same table (the nested
learning curves and noise settings only in the JSON lines). ``DIR/sweep.toml`` is the sweep file as run.
"""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

from ...errors import SweepError
from .cells import COLUMNS
from .spec import SweepSpec

RESULTS = "results.jsonl"


class ResultStore:
    """The rows of one output directory; see the module docstring."""

    def __init__(self, out_dir: str | Path):
        self.dir = Path(out_dir)
        self.path = self.dir / RESULTS

    def open(self, spec: SweepSpec, resume: bool, retry_failed: bool = False) -> dict[str, dict]:
        """Prepare the directory; return the rows already finished (by cell id) that need not run again.

        Without ``resume``, a directory that holds results is refused rather than overwritten. With it,
        a line cut short by the interruption is dropped; ``retry_failed`` runs failed and timed-out cells
        again."""
        self.dir.mkdir(parents=True, exist_ok=True)
        done: dict[str, dict] = {}
        if self.path.exists() and self.path.stat().st_size and not resume:
            raise SweepError("holds a sweep's results already: give --resume to go on with it, or another "
                             "output directory", str(self.dir))
        if resume and self.path.exists():
            done = {row["cell_id"]: row for row in self._read()}
            self._write(done.values())  # without a torn last line, so appending starts on a fresh line
            if retry_failed:
                done = {k: row for k, row in done.items() if row["status"] == "ok"}
        (self.dir / "sweep.toml").write_text(spec.text)
        return done

    def append(self, row: dict) -> None:
        with self.path.open("a", encoding="utf-8") as f:
            f.write(json.dumps(row) + "\n")

    def finish(self, spec: SweepSpec, rows: dict[str, dict]) -> list[dict]:
        """Rewrite the table in grid order (the grid's cells only) as JSON lines and CSV; return it."""
        table = [rows[c.id] for c in spec.cells if c.id in rows]
        self._write(table)
        tmp = self.dir / "results.csv.tmp"
        with tmp.open("w", newline="", encoding="utf-8") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(table)
        os.replace(tmp, self.dir / "results.csv")
        return table

    def _read(self) -> list[dict]:
        rows = []
        with self.path.open(encoding="utf-8") as f:
            for line in f:
                try:
                    row = json.loads(line)
                except json.JSONDecodeError:
                    continue  # the line being written when the sweep was stopped
                if isinstance(row, dict) and "cell_id" in row:
                    rows.append(row)
        return rows

    def _write(self, rows) -> None:
        tmp = self.path.with_suffix(".jsonl.tmp")
        tmp.write_text("".join(json.dumps(r) + "\n" for r in rows), encoding="utf-8")
        os.replace(tmp, self.path)
