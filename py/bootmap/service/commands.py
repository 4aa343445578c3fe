"""The ``serve`` and ``token`` sub-commands; :func:`register` adds them to the ``bootmap`` command.

Exit codes: 0 after a clean shutdown, 2 for bad settings or axioms that do not load (the message says
which), 1 if the server fails.
"""

from __future__ import annotations

import argparse
import errno
import os
import sys

from ..errors import EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_OK, error_line


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
                   help="seconds per solve (default 60, as bootmap map)")
    p.add_argument("--require-tokens", action="store_true", default=None,
                   help="every request needs an API token (always so when --host is not loopback)")
    p.add_argument("--runs-dir", metavar="DIR", help="experiment runs whose figures the viewer shows (read-only)")
    p.set_defaults(handler=cmd_serve)

    t = subparsers.add_parser("token", help="make API tokens for the HTTP service",
                              description="Manage the service's API tokens, in the database `bootmap serve` uses.")
    tsub = t.add_subparsers(dest="token_command", required=True, metavar="ACTION")
    c = tsub.add_parser("create", help="make a token; it is printed once, on the last line",
                        description="Make an API token named NAME. Only its hash is stored: the token is printed "
                                    "once, on the last line. Send it as 'Authorization: Bearer <token>'.")
    c.add_argument("name", metavar="NAME", help="who the token is for (letters, digits, _ . @ -)")
    c.add_argument("--admin", action="store_true", help="the token may reload axioms and make tokens, and reads "
                                                        "and changes every tableau")
    c.set_defaults(handler=cmd_token_create)
    ls = tsub.add_parser("list", help="list the tokens: name, admin or not, when made, tableaux owned",
                         description="List the API tokens (never the tokens themselves: only their hashes are "
                                     "stored): name, whether it is an admin's, when it was made, and how many "
                                     "tableaux it owns.")
    ls.set_defaults(handler=cmd_token_list)
    rv = tsub.add_parser("revoke", help="revoke a token: refused from now on, on every server",
                         description="Revoke the token named NAME: every server refuses it from now on. Its "
                                     "tableaux stay, owned by no one (admin tokens reach them).")
    rv.add_argument("name", metavar="NAME", help="the token's name, as `bootmap token list` shows it")
    rv.set_defaults(handler=cmd_token_revoke)
    for action in (c, ls, rv):
        action.add_argument("--db", metavar="PATH_OR_URL",
                            help="SQLite file or SQLAlchemy URL (default DATA_DIR/bootmap.sqlite3)")
        action.add_argument("--data-dir", metavar="DIR", help="data directory (default ~/.local/share/bootmap)")


def cmd_serve(args: argparse.Namespace) -> int:
    from pydantic import ValidationError

    from ..errors import AxiomError
    from ..mapping.theory import load_theory
    from .settings import Settings

    given = {"host": args.host, "port": args.port, "db": args.db, "data_dir": args.data_dir,
             "axioms": args.axioms, "solve_time_limit_s": args.solve_time_limit_s,
             "require_tokens": args.require_tokens, "runs_dir": args.runs_dir}
    try:
        settings = Settings(**{k: v for k, v in given.items() if v is not None})
        if settings.host in ("0.0.0.0", "::", "") and not settings.allowed_hosts:
            print(error_line("serve", f"listening on {settings.host or 'every interface'} needs "
                             "BOOTMAP_ALLOWED_HOSTS: the host names clients use (or '*' behind a proxy that checks "
                             "them)", EXIT_BAD_INPUT), file=sys.stderr)
            return EXIT_BAD_INPUT
        load_theory(settings.axioms)  # fail here, with the message, rather than inside uvicorn's start-up
        settings.data_dir.mkdir(parents=True, exist_ok=True)
        _check_spool_dir(settings.spool_dir)
    except ValidationError as e:
        print(error_line("serve", f"bad setting: {_first_error(e)}", EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT
    except (AxiomError, OSError) as e:
        print(error_line("serve", e, EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT
    import uvicorn

    from .app import create_app
    from .connections import with_header_deadline

    uvicorn.run(create_app(settings), host=settings.host, port=settings.port, log_level=settings.log_level,
                timeout_graceful_shutdown=5, http=with_header_deadline(settings.header_timeout_s))
    return EXIT_OK


def _on_tokens(args: argparse.Namespace, command: str, failing: str, act):
    """``act(store)`` on the token database the command names (``--db``, ``--data-dir``), the store closed
    after: ``(EXIT_OK, act's value, where the database is)``, or the exit code once the error is printed (a
    bad setting, a name taken or unknown: bad input; a database that cannot be reached: ``failing``)."""
    from pydantic import ValidationError
    from sqlalchemy.engine import make_url

    from .settings import Settings
    from .store import Conflict, NotFound, Store

    given = {"db": args.db, "data_dir": args.data_dir}
    try:
        settings = Settings(**{k: v for k, v in given.items() if v is not None})
    except ValidationError as e:
        print(error_line(command, f"bad setting: {_first_error(e)}", EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT, None, None
    try:
        store = Store(settings.database_url, settings.sqlite_busy_timeout_s)
        try:
            value = act(store)
        finally:
            store.close()
    except (Conflict, NotFound) as e:
        print(error_line(command, e, EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT, None, None
    except Exception as e:  # noqa: BLE001  the database cannot be reached, read or written: a failure
        print(error_line(command, f"{failing}: {e}", EXIT_FAILURE), file=sys.stderr)
        return EXIT_FAILURE, None, None
    return EXIT_OK, value, make_url(settings.database_url).render_as_string(hide_password=True)


def cmd_token_create(args: argparse.Namespace) -> int:
    import re

    from .auth import digest, new_token

    if not re.fullmatch(r"[A-Za-z0-9_.@-]{1,100}", args.name):
        print(error_line("token create", f"bad name {args.name!r}: use 1-100 letters, digits, _ . @ -",
                         EXIT_BAD_INPUT), file=sys.stderr)
        return EXIT_BAD_INPUT
    token = new_token()
    code, _, where = _on_tokens(args, "token create", "cannot store the token",
                                lambda store: store.add_token(args.name, digest(token), args.admin))
    if code != EXIT_OK:
        return code
    print(f"made {'admin token' if args.admin else 'token'} {args.name!r} in {where}; it is shown only now:")
    print(token)
    return EXIT_OK


def cmd_token_list(args: argparse.Namespace) -> int:
    code, tokens, where = _on_tokens(args, "token list", "cannot read the tokens", lambda store: store.tokens())
    if code != EXIT_OK:
        return code
    print(f"{len(tokens)} token(s) in {where}")
    for t in tokens:
        print(f"{t.name:30s} {'admin' if t.admin else 'user ':5s}  made {t.created_at:%Y-%m-%d %H:%M} UTC  "
              f"{t.tableaux} tableau(x)")
    return EXIT_OK


def cmd_token_revoke(args: argparse.Namespace) -> int:
    code, _, where = _on_tokens(args, "token revoke", "cannot revoke the token",
                                lambda store: store.delete_token(args.name))
    if code != EXIT_OK:
        return code
    print(f"revoked token {args.name!r} in {where}: refused from now on; its tableaux stay, owned by no one")
    return EXIT_OK


def _check_spool_dir(directory) -> None:
    """The directory request bodies are spooled to (``spool_dir``) can be made and written to: else an
    OSError naming the setting, before uvicorn starts."""
    if directory is None:
        return
    try:
        directory.mkdir(parents=True, exist_ok=True)
        if not os.access(directory, os.W_OK | os.X_OK):
            raise PermissionError(errno.EACCES, "not writable")
    except OSError as e:
        raise OSError(f"spool_dir (BOOTMAP_SPOOL_DIR) {directory}: {e.strerror or e}") from None


def _first_error(e) -> str:
    err = e.errors()[0]
    name = ".".join(str(x) for x in err["loc"])
    return f"{name} (BOOTMAP_{name.upper()}): {err['msg']}"
