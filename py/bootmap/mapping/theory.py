"""The theory: the .lp files of the axiom directory, grouped into levels.

Every ``*.lp`` file at the top of the axiom directory is a *level*, named by its file stem
(``causal``, ``topological``, ``metrical``, or any file a user drops in, e.g. ``daylight.lp``).
Files under ``core/`` lay out the search and are always loaded. Rules are named by a ``%! name``
comment line directly above them; :meth:`Theory.rules` lists them with file and line, which is
how explanations cite the axiom a proof uses.

The directory is, in order: the ``axioms`` argument, the ``BOOTMAP_AXIOMS`` environment variable,
the copy inside an installed wheel (``bootmap/asp``), the repository's top-level ``asp/``.
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Iterable, Sequence

import clingo

from ..errors import AxiomError

MANDATORY = "causal"
_RULE_NAME = re.compile(r"^%!\s*([a-z][a-z0-9_]*)\s*$")


def default_axioms_dir() -> Path:
    """Where the axioms are when nobody says otherwise."""
    env = os.environ.get("BOOTMAP_AXIOMS")
    if env:
        return Path(env)
    package = Path(__file__).resolve().parent.parent  # bootmap/
    for candidate in (package / "asp", package.parent.parent / "asp"):
        if (candidate / f"{MANDATORY}.lp").is_file():
            return candidate
    raise AxiomError("cannot find the axiom directory (asp/); set BOOTMAP_AXIOMS or pass --axioms")


@dataclass(frozen=True)
class Rule:
    """A named rule: where it is and what it says."""

    name: str
    level: str
    file: str
    line: int
    text: str


@dataclass(frozen=True)
class Theory:
    """The loaded axiom files. ``levels`` maps level name -> file; ``core`` lists the search files."""

    directory: Path
    levels: dict[str, Path]
    core: tuple[Path, ...]

    @property
    def files(self) -> list[Path]:
        return list(self.core) + list(self.levels.values())

    def load_into(self, ctl: clingo.Control, leave_out: Iterable[str] = ()) -> None:
        """Load the files into ``ctl``; the levels named in ``leave_out`` are not loaded."""
        skip = {self.levels[name] for name in leave_out}
        for f in self.files:
            if f not in skip:
                ctl.load(str(f))

    @cached_property
    def map_levels(self) -> tuple[str, ...]:
        """The levels that judge the map alone: every rule reads only the map's transitions and dstates
        (``next/3``, ``dstate/1``) and what the level itself derives from them, no choice, optimisation or
        external is in it, and no other file reads or defines what it derives. Such a level (the
        topological one) says the same of every labelling of one partition, so the search may leave it
        out and ask it of each map it finds (:mod:`.mapcheck`). A level a user adds qualifies by the same
        test; one that reads the time points does not."""
        parsed = {name: _program_of(path) for name, path in self.levels.items()}
        others = {path: _program_of(path) for path in self.core}
        found = []
        for name, program in parsed.items():
            if not program.judges_map:
                continue
            rest = [p for n, p in parsed.items() if n != name] + list(others.values())
            if not any(program.defines & (p.reads | p.defines) for p in rest):
                found.append(name)
        return tuple(found)

    @cached_property
    def monotone_levels(self) -> tuple[str, ...]:
        """The levels of :attr:`map_levels` whose file says ``% Monotone:`` in a comment line: a map they
        reject stays rejected when dstates and transitions are added to it, and whatever its dstates are
        called. The search then learns, from a map they reject, that every map with the same few
        transitions, or a renaming of them, is rejected (:mod:`.mapcheck`, :mod:`.search.exact`). A level's
        own word, as its rules' meaning is (the stock topological level's is tested on random maps); a
        user level that does not say it is asked of each map as it is, never generalised from."""
        return tuple(name for name in self.map_levels if _says_monotone(self.levels[name]))

    def rules(self) -> list[Rule]:
        """Every ``%! name`` labelled rule, in file order."""
        out = []
        for level, path in [("core", p) for p in self.core] + list(self.levels.items()):
            out.extend(_labelled_rules(path, level))
        return out


def axiom_files(directory: Path) -> tuple[dict[str, Path], tuple[Path, ...]]:
    """The files of an axiom directory: its levels (the top-level ``.lp`` files, by name, sorted) and its
    core (``core/*.lp``, sorted). The one place that says which files a theory is made of."""
    if not directory.is_dir():
        raise AxiomError(f"axiom directory not found: {directory}")
    return {p.stem: p for p in sorted(directory.glob("*.lp"))}, tuple(sorted((directory / "core").glob("*.lp")))


def available_levels(directory: str | Path | None = None) -> list[str]:
    d = Path(directory) if directory else default_axioms_dir()
    return sorted(axiom_files(d)[0]) if d.is_dir() else []


def load_theory(directory: str | Path | None = None, levels: Sequence[str] | None = None) -> Theory:
    """Find, select and check the axiom files. Raises :class:`AxiomError` with clingo's message."""
    d = Path(directory) if directory else default_axioms_dir()
    found, core = axiom_files(d)
    if MANDATORY not in found:
        raise AxiomError(f"{d} has no {MANDATORY}.lp: the causal level defines the dstates")
    chosen = list(found) if levels is None else select_levels(levels, list(found), str(d))
    theory = Theory(d, {name: found[name] for name in chosen}, core)
    check_syntax(theory.files)
    return theory


def select_levels(levels: Iterable[str], available: Sequence[str], where: str = "the theory") -> list[str]:
    """The levels asked for, checked against those ``where`` has: unknown ones and a missing causal level
    raise AxiomError."""
    chosen = [lv.strip() for lv in levels if lv.strip()]
    unknown = [lv for lv in chosen if lv not in available]
    if unknown:
        raise AxiomError(f"unknown level(s) {', '.join(unknown)}; {where} has: {', '.join(available)}")
    if MANDATORY not in chosen:
        raise AxiomError(f"the {MANDATORY} level cannot be switched off: it defines what a dstate is")
    return chosen


def check_syntax(files: Iterable[Path]) -> None:
    """Parse every file with clingo; a file that does not parse raises AxiomError with clingo's words."""
    for f in files:
        messages: list[str] = []
        ctl = clingo.Control(["--warn=none"], logger=lambda _code, msg: messages.append(msg.strip()))
        try:
            ctl.load(str(f))
        except RuntimeError as e:  # some errors (e.g. #script without Python support) reach only the exception
            said = [m for m in messages if m] or [str(e).strip() or "clingo gave no reason"]
            raise AxiomError(f"{f} does not parse:\n" + "\n".join(said)) from None


#: What a level that judges the map may read from the others: the map's transitions and its dstates.
MAP_INPUTS = frozenset({("next", 3), ("dstate", 1)})


@dataclass(frozen=True)
class _Program:
    """What a file's rules derive (``defines``) and read (``reads``, ``#show`` included), as (name, arity);
    and whether its statements are all of the kinds a level that judges the map may have (plain rules and
    constraints, ``#show``, ``#const``, comments, the base part)."""

    defines: frozenset
    reads: frozenset
    shows: frozenset
    plain: bool

    @property
    def judges_map(self) -> bool:
        return (self.plain and bool(self.defines) and self.reads - self.defines <= MAP_INPUTS
                and not self.shows & MAP_INPUTS)


def _program_of(path: Path) -> _Program:
    """What a file's rules derive and read (:func:`.vocabulary.signatures`, clingo's own parser), and whether
    its statements are plain; parsed again only when the file changed (its size or modification time)."""
    stat = Path(path).stat()
    return _parsed(str(path), stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=64)
def _parsed(path: str, _mtime_ns: int, _size: int) -> _Program:
    from clingo import ast

    from .vocabulary import signatures

    shows: set[tuple[str, int]] = set()
    plain = True
    allowed = {ast.ASTType.Rule, ast.ASTType.ShowSignature, ast.ASTType.Definition, ast.ASTType.Comment,
               ast.ASTType.Program}

    def visit(stmt) -> None:
        nonlocal plain
        kind = stmt.ast_type
        if kind not in allowed or (kind == ast.ASTType.Program and stmt.name != "base"):
            plain = False  # a minimize, an external, a show-term, a script, another program part ...
        elif kind == ast.ASTType.Rule and (stmt.head.ast_type != ast.ASTType.Literal
                                           or stmt.head.sign != ast.Sign.NoSign):
            plain = False  # a choice, a disjunction, an aggregate or a negated head: not a plain rule
        elif kind == ast.ASTType.ShowSignature:
            shows.add((stmt.name, stmt.arity))

    defines, used, _ = signatures([path], also=visit)
    return _Program(frozenset(defines), frozenset(used | shows), frozenset(shows), plain)


_MONOTONE = re.compile(r"^%\s*Monotone:")


def _says_monotone(path: Path) -> bool:
    """Whether a level file declares itself monotone (a comment line starting ``% Monotone:``)."""
    return any(_MONOTONE.match(line) for line in Path(path).read_text().splitlines())


def _labelled_rules(path: Path, level: str) -> list[Rule]:
    return [Rule(name, level, str(path), label + 1, " ".join(text for _, text in body))
            for name, label, body in _label_blocks(path)]


def rule_lines(path: Path) -> dict[int, str]:
    """Line number -> the name of the labelled rule on that line (explanations cite rules by line)."""
    return {n: name for name, _, body in _label_blocks(path) for n, _ in body}


def _label_blocks(path: Path):
    """Each ``%! name`` label with its line number and the lines it names: (line number, text) up to the
    next blank or comment line (possibly several rules under one name)."""
    lines = Path(path).read_text().splitlines()
    for i, line in enumerate(lines):
        m = _RULE_NAME.match(line.strip())
        if not m:
            continue
        body = []
        for j in range(i + 1, len(lines)):
            if not lines[j].strip() or lines[j].lstrip().startswith("%"):
                break
            body.append((j + 1, lines[j].strip()))
        yield m.group(1), i + 1, body


#: The shipped axiom files (path in the axiom directory -> sha256): what bootmap.mapping.replay's argument
#: and bootmap.mapping.topology's reading of the topological level are about. When one changes, check the
#: replay's argument and the reading against it, then update its digest (tests/mapping/test_stream.py,
#: tests/mapping/test_topology.py).
STOCK_DIGESTS = {
    "causal.lp": "c53ada773c9738d3654228e1c660ac260badc953658d8500509d83f0c2c4f473",
    "metrical.lp": "4628513194f19408c98f56c8d15750bd6f1cb69f46904f76d5521ada01d6dbb5",
    "topological.lp": "729a309a6a1c99d71f9769994c8d83671d5bdf02b740bfac88e3f71b7759cb71",
    "core/ask.lp": "2e8adf403568adf1bc5e166b19bde32ba2fdaac7f873adef0930bb9071c939ca",
    "core/partition.lp": "f02aad45d48ee30e03278067ded3427cc71ea3ac02fd7bd4e4d31b13351ca51a",
    "core/assert.lp": "2c01befdceb28aa69c8a639e07b55dc2b96f6280fd2d7f052fe55fa211a76c17",
    "core/prepass.lp": "7c0467733eb5c9806a227948479ee56cca2bf41d51a193d0f00b736594110478",
}


def digest(path: Path) -> str:
    """The sha256 of a file, in hex (as ``STOCK_DIGESTS`` records the shipped ones)."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def covers(theory: Theory) -> bool:
    """Every file of the theory is a stock axiom file, unchanged (a subset of the levels will do)."""
    for f in theory.files:
        name = f.relative_to(theory.directory).as_posix()
        if STOCK_DIGESTS.get(name) != digest(f):
            return False
    return True
