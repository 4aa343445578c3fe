"""Targets for the benchmarks: each measured figure printed beside its target, and an exit status.

A bench script makes one :class:`Targets`, calls :meth:`Targets.check` for every figure that has a
target (the line is printed at once, e.g. ``ours / RPNI, 401 steps: 7.6x (target <= 10x: ok)``), and
ends with ``sys.exit(targets.exit_status())``: 0 when every target is met, 1 when any is missed (the
missed ones are listed again at the end).
"""

from __future__ import annotations

import operator

_OPS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge, "==": operator.eq}


class Targets:
    def __init__(self) -> None:
        self.met: list[str] = []
        self.missed: list[str] = []

    def check(self, name: str, value, op: str, bound, fmt: str = "{:.3g}", unit: str = "",
              bound_text: str | None = None) -> bool:
        """Print ``name: value (target op bound: ok|MISSED)`` and remember the outcome.

        ``fmt`` formats the measured value; the bound is printed as ``bound_text`` if given, else as
        written (``{:g}``) followed by ``unit``. A ``value`` of None (the figure could not be measured)
        misses its target."""
        ok = value is not None and bool(_OPS[op](value, bound))
        shown = "not measured" if value is None else fmt.format(value) + unit
        if value is not None and not ok and fmt.format(value) == fmt.format(bound):
            # rounded as the bound, it would read as met: as many digits as tell the two apart
            digits = next((d for d in range(3, 13) if f"{value:.{d}g}" != f"{bound:.{d}g}"), 12)
            shown = f"{value:.{digits}g}{unit}"
        target = bound_text if bound_text is not None else f"{bound:g}{unit}"
        line = f"{name}: {shown} (target {op} {target}: {'ok' if ok else 'MISSED'})"
        (self.met if ok else self.missed).append(line)
        print(line, flush=True)
        return ok

    def exit_status(self) -> int:
        """Print how many targets were met; 0 if all, else 1 after listing the missed ones."""
        total = len(self.met) + len(self.missed)
        if not self.missed:
            print(f"\ntargets: all {total} met")
            return 0
        print(f"\ntargets: {len(self.missed)} of {total} MISSED:")
        for line in self.missed:
            print(f"  {line}")
        return 1
