"""The ``serve`` sub-command; :func:`register` adds it to the ``bootmap`` command.

Exit codes: 0 after a clean shutdown, 2 for bad settings or axioms that do not load (the message says
which), 1 if the server fails.
"""

from __future__ import annotations

import argparse
import sys

from ..errors import EXIT_BAD_INPUT, EXIT_OK


def register(subparsers) -> None:
    """Add ``serve`` to an ``argparse`` sub-parsers object."""
    p = subparsers.add_parser(
        "serve", help="run the HTTP service (post tableaux, get maps; OpenAPI docs at /docs)",
        description="Run the HTTP service with uvicorn. Options override BOOTMAP_* environment variables "
                    "(e.g. BOOTMAP_MAX_STEPS, BOOTMAP_SOLVE_TIME_LIMIT_S); see docs/service.md for all settings.")
    p.add_argument("--host", help="interface to listen on (default 127.0.0.1)")
    p.add_argument("--port", type=int, help="port (default 8000; 0 picks a free one, logged at start-up)")
    p.add_argument("--db", metavar="PATH_OR_URL",
                   help="SQLite file or SQLAlchemy URL (default DATA_DIR/bootmap.sqlite3)")
    p.add_argument("--data-dir", metavar="DIR", help="data directory (default ~/.local/share/bootmap)")
    p.add_argument("--axioms", metavar="DIR", help="axiom directory (default: the shipped asp/)")
    p.add_argument("--time-limit", type=float, metavar="S", dest="solve_time_limit_s",
                   help="seconds per solve (default 30)")
    p.set_defaults(handler=cmd_serve)


def cmd_serve(args: argparse.Namespace) -> int:
    from pydantic import ValidationError

    from ..errors import AxiomError
    from ..mapping.theory import load_theory
    from .settings import Settings

    given = {"host": args.host, "port": args.port, "db": args.db, "data_dir": args.data_dir,
             "axioms": args.axioms, "solve_time_limit_s": args.solve_time_limit_s}
    try:
        settings = Settings(**{k: v for k, v in given.items() if v is not None})
        load_theory(settings.axioms)  # fail here, with the message, rather than inside uvicorn's start-up
        settings.data_dir.mkdir(parents=True, exist_ok=True)
    except ValidationError as e:
        print(f"bootmap serve: bad setting: {_first_error(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (AxiomError, OSError) as e:
        print(f"bootmap serve: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    import uvicorn

    from .app import create_app

    uvicorn.run(create_app(settings), host=settings.host, port=settings.port, log_level=settings.log_level,
                timeout_graceful_shutdown=5)
    return EXIT_OK


def _first_error(e) -> str:
    err = e.errors()[0]
    name = ".".join(str(x) for x in err["loc"])
    return f"{name} (BOOTMAP_{name.upper()}): {err['msg']}"
