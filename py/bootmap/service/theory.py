"""The theory the service solves with: a checked snapshot of the axiom directory.

The library reads the ``.lp`` files at every solve, so a user editing ``asp/`` would change (or break)
the running service's theory in the middle of its work. The service instead copies the axiom files,
checks the copy with clingo, and solves only with copies that parse: ``DATA_DIR/theories/<id>/``, where
the id is a hash of the files' names and contents (stored maps record it). A reload makes a new
snapshot; if a file does not parse, the reload fails with clingo's message and the old theory stays.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import threading
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from ..errors import AxiomError
from ..mapping.theory import Theory, axiom_files, default_axioms_dir, load_theory


@dataclass(frozen=True)
class LoadedTheory:
    id: str
    source: Path
    snapshot: Path
    theory: Theory
    loaded: datetime = field(default_factory=lambda: datetime.now(timezone.utc))

    def listing(self) -> dict:
        """The files, their levels and named rules (files relative to the axiom directory)."""
        rules = self.theory.rules()
        files = []
        for level, path in [("core", p) for p in self.theory.core] + list(self.theory.levels.items()):
            files.append({"level": level, "file": str(path.relative_to(self.snapshot)),
                          "rules": [{"name": r.name, "line": r.line, "text": r.text}
                                    for r in rules if Path(r.file) == path]})
        # The name only: the server's file system layout is nobody else's business.
        return {"theory": self.id, "directory": self.source.name, "loaded": self.loaded,
                "levels": list(self.theory.levels), "files": files}


def _axiom_files(source: Path) -> dict[str, bytes]:
    """What ``load_theory`` reads (``axiom_files``): the levels and the core, by relative path."""
    levels, core = axiom_files(source)
    paths = list(levels.values()) + list(core)
    try:
        return {str(p.relative_to(source)): p.read_bytes() for p in paths}
    except OSError as e:
        raise AxiomError(f"cannot read the axioms: {e}") from None


class Theories:
    """The current theory snapshot, and reloading it from the axiom directory."""

    def __init__(self, source: str | Path | None, data_dir: Path):
        self.source = Path(source).resolve() if source else default_axioms_dir().resolve()
        self.root = Path(data_dir) / "theories"
        self._lock = threading.Lock()
        self.current = self._snapshot()

    def reload(self) -> LoadedTheory:
        """Snapshot the axiom directory again. On AxiomError the current theory is kept."""
        with self._lock:
            self.current = self._snapshot()
            return self.current

    def _snapshot(self) -> LoadedTheory:
        files = _axiom_files(self.source)
        digest = hashlib.sha256()
        for name, content in files.items():
            digest.update(name.encode() + b"\0" + hashlib.sha256(content).digest())
        theory_id = digest.hexdigest()[:16]
        snapshot = self.root / theory_id
        if not snapshot.is_dir():
            self._write(files, snapshot)
        return LoadedTheory(theory_id, self.source, snapshot, load_theory(snapshot))

    def _write(self, files: dict[str, bytes], snapshot: Path) -> None:
        """Write and check a snapshot in a scratch directory, then move it into place in one rename."""
        self.root.mkdir(parents=True, exist_ok=True)
        scratch = Path(tempfile.mkdtemp(dir=self.root, prefix=".new-"))
        try:
            for name, content in files.items():
                (scratch / name).parent.mkdir(parents=True, exist_ok=True)
                (scratch / name).write_bytes(content)
            try:
                load_theory(scratch)
            except AxiomError as e:  # name the user's files, not the scratch copy
                raise AxiomError(str(e).replace(str(scratch), str(self.source))) from None
            try:
                os.rename(scratch, snapshot)
            except OSError:
                if not snapshot.is_dir():  # not just another reload that got there first
                    raise
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
