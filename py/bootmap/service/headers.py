"""Security headers on every response: a strict Content-Security-Policy and its companions.

The map viewer shows strings that users posted (view labels, run names). It puts them on the page as
text, never as HTML; the policy is the second wall (defence in depth): should a hostile label ever reach
the page as markup, the browser runs no inline script or handler, no ``eval``, and loads nothing from
elsewhere. Every response gets the headers, JSON and errors included (a JSON answer opened in a tab is
a page too):

- ``Content-Security-Policy``: :data:`POLICY`; ``frame-ancestors 'none'`` and ``X-Frame-Options: DENY``
  (no other site may frame a page of the service and trick a click);
- ``X-Content-Type-Options: nosniff`` (a browser takes a JSON or PNG answer for what it says it is);
- ``Referrer-Policy: no-referrer`` (a tableau's URL goes nowhere else).

FastAPI's API docs (``/docs``: Swagger UI, ``/redoc``: ReDoc, and Swagger's OAuth2 redirect page) load
their code from cdn.jsdelivr.net and start it with an inline script. Each of those pages gets a policy
of its own (:func:`docs_policies`) that allows exactly the scripts its HTML names and its inline script
by SHA-256 hash, computed from the HTML FastAPI writes for this app; no other inline script runs there.

:class:`SecurityHeaders` is pure ASGI: it rewrites only a response's start message, so streamed bodies
and 304s pass through untouched. :func:`wrap` puts it around the whole application, outside even
Starlette's own error middleware, so an unexpected error's 500 carries the headers too.
"""

from __future__ import annotations

import base64
import hashlib
import re
from urllib.parse import urlsplit

from fastapi import FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html, get_swagger_ui_oauth2_redirect_html
from starlette.types import ASGIApp, Message, Receive, Scope, Send

# The viewer's page and the API. The page's own scripts and stylesheet only; images from the service
# itself, the page's data: favicon and blob: object URLs (figures fetched with the token); requests to
# the service only; no <base>, no form sent elsewhere, never framed. Styles set from scripts through
# element.style (CSSOM) need no 'unsafe-inline'.
POLICY = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
          "connect-src 'self'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'")

HEADERS = {"content-security-policy": POLICY, "x-content-type-options": "nosniff", "x-frame-options": "DENY",
           "referrer-policy": "no-referrer"}


class SecurityHeaders:
    """Set :data:`HEADERS` on every HTTP response (replacing any of them the app set); the paths in
    ``policies`` get their own Content-Security-Policy instead of :data:`POLICY`."""

    def __init__(self, app: ASGIApp, policies: dict[str, str] | None = None):
        self.app = app
        self.headers = _encode(HEADERS)
        self.per_path = {path: _encode({**HEADERS, "content-security-policy": policy})
                         for path, policy in (policies or {}).items()}

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        ours = self.per_path.get(scope["path"], self.headers)
        names = {name for name, _ in ours}

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                kept = [(k, v) for k, v in message.get("headers", []) if k.lower() not in names]
                message = {**message, "headers": kept + ours}
            await send(message)

        await self.app(scope, receive, send_with_headers)


def _encode(headers: dict[str, str]) -> list[tuple[bytes, bytes]]:
    return [(k.encode("latin-1"), v.encode("latin-1")) for k, v in headers.items()]


def wrap(app: FastAPI) -> None:
    """Make :class:`SecurityHeaders` the outermost layer of ``app``: around the stack Starlette builds
    (its error middleware, then the app's own middleware, then the routes), so that no response, not
    even an unexpected error's 500, leaves without the headers."""
    policies = docs_policies(app)
    build = app.build_middleware_stack
    app.build_middleware_stack = lambda: SecurityHeaders(build(), policies)  # type: ignore[method-assign]


def docs_policies(app: FastAPI) -> dict[str, str]:
    """The policy of each API docs page, from the HTML FastAPI serves there (as FastAPI's own routes
    write it for this app; the service runs at the root, so no root_path enters their URLs)."""
    pages: dict[str, str] = {}
    if app.openapi_url and app.docs_url:
        pages[app.docs_url] = get_swagger_ui_html(
            openapi_url=app.openapi_url, title=f"{app.title} - Swagger UI",
            oauth2_redirect_url=app.swagger_ui_oauth2_redirect_url, init_oauth=app.swagger_ui_init_oauth,
            swagger_ui_parameters=app.swagger_ui_parameters).body.decode()
        if app.swagger_ui_oauth2_redirect_url:
            pages[app.swagger_ui_oauth2_redirect_url] = get_swagger_ui_oauth2_redirect_html().body.decode()
    if app.openapi_url and app.redoc_url:
        pages[app.redoc_url] = get_redoc_html(openapi_url=app.openapi_url, title=f"{app.title} - ReDoc").body.decode()
    return {path: docs_policy(html) for path, html in pages.items()}


INLINE_SCRIPT = re.compile(r"<script>(.*?)</script>", re.DOTALL)
SCRIPT_SRC = re.compile(r"<script\s[^>]*\bsrc=\"([^\"]+)\"")
LINK = re.compile(r"<link\s[^>]*>")


def docs_policy(html: str) -> str:
    """A docs page's policy: its inline scripts by hash and the script files it names, exactly; its
    stylesheets' and icon's hosts (and Google's font files when it links Google's font stylesheet);
    inline styles (Swagger UI and ReDoc set styles from their code, which cannot carry a hash; no user
    data is on these pages); ReDoc's search worker (a blob: URL); requests to the service only. Never
    framed, no <base>, no form sent elsewhere."""
    hashes = [f"'sha256-{base64.b64encode(hashlib.sha256(s.encode()).digest()).decode()}'"
              for s in INLINE_SCRIPT.findall(html)]
    scripts = [_without_query(url) for url in SCRIPT_SRC.findall(html)]
    links = [(_attribute(tag, "rel"), _origin(_attribute(tag, "href"))) for tag in LINK.findall(html)]
    styles = sorted({origin for rel, origin in links if "stylesheet" in rel})
    icons = sorted({origin for rel, origin in links if "icon" in rel})
    fonts = ["https://fonts.gstatic.com"] if "https://fonts.googleapis.com" in styles else ["'none'"]
    return "; ".join(" ".join(directive) for directive in [
        ["default-src", "'none'"], ["script-src", *hashes, *scripts], ["style-src", "'unsafe-inline'", *styles],
        ["img-src", "'self'", "data:", *icons], ["font-src", *fonts], ["worker-src", "blob:"],
        ["connect-src", "'self'"], ["base-uri", "'none'"], ["form-action", "'self'"], ["frame-ancestors", "'none'"]])


def _attribute(tag: str, name: str) -> str:
    found = re.search(rf"\b{name}=\"([^\"]*)\"", tag)
    return found.group(1) if found else ""


def _origin(url: str) -> str:
    parts = urlsplit(url)
    return f"{parts.scheme}://{parts.netloc}"


def _without_query(url: str) -> str:
    """A URL as a CSP source: scheme, host and path (a source has no query)."""
    parts = urlsplit(url)
    return f"{parts.scheme}://{parts.netloc}{parts.path}"
