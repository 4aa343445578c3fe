"""Package faces that import their modules when a name is first used (PEP 562).

A command line registers every sub-command before any is run; a package whose ``__init__`` imported its
modules would load the physics, scipy or clingo just to build ``bootmap --help``. With
:func:`exports`, ``from bootmap.sim import run`` still works, and costs its import only then.

Example
-------
>>> getattr_ = exports("json", {"dumps": "json"})
>>> getattr_("dumps")({"a": 1})
'{"a": 1}'
"""

from __future__ import annotations

import sys
from importlib import import_module
from typing import Callable


def exports(package: str, homes: dict[str, str]) -> Callable[[str], object]:
    """A module ``__getattr__`` for ``package`` whose names live in the modules ``homes`` gives (relative
    to ``package`` when they start with a dot); each is imported when first asked for, and kept."""
    def __getattr__(name: str):
        if name not in homes:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(homes[name], package), name)
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__
