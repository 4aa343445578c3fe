"""The README's shown commands and what it says they print: each ``` block whose first line is
``$ bootmap ...``. A test runs the command and finds the shown text in what it printed."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: Figures that differ from run to run: seconds, and solver timings.
_TIMES = re.compile(r"\d+(\.\d+)? s\b")


def shown_commands() -> list[tuple[list[str], str]]:
    """(the command's arguments after ``bootmap``, the text shown below it) for every such block."""
    text = (ROOT / "README.md").read_text()
    return [(shlex.split(cmd)[1:], shown) for cmd, shown in re.findall(r"```\n\$ (bootmap [^\n]*)\n(.*?)```", text, re.S)]


def _flat(text: str) -> str:
    return _TIMES.sub("<t> s", " ".join(text.split()))


def missing(shown: str, printed: str) -> list[str]:
    """The fragments of ``shown`` (split at ``...``, where the README leaves lines out) that do not appear,
    in order, in ``printed``: whitespace and line breaks aside, seconds aside."""
    out, at, lost = _flat(printed), 0, []
    for fragment in (_flat(f) for f in shown.split("...")):
        if not fragment:
            continue
        where = out.find(fragment, at)
        if where < 0:
            lost.append(fragment)
        else:
            at = where + len(fragment)
    return lost
