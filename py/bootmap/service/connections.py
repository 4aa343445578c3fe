"""What one connection may cost the server in time: a deadline for its request's line and headers, and
one for each part of its response.

uvicorn closes a kept-alive connection idle for 5 s, and BodyLimit (problems.py) answers a body that is
too slow with 408. Two ways to hold a connection stay open without these:

- sending the request line and headers a byte at a time (slow-loris): :func:`with_header_deadline`
  makes uvicorn's HTTP/1.1 protocol close a connection whose request headers are not complete within
  ``header_timeout_s`` of its first byte (or of the connection, for a client that sends nothing);
- not reading the response: :class:`SendTimeout` ends a response that cannot go out for
  ``send_timeout_s`` (the client's receive window and the server's buffers are full).
"""

from __future__ import annotations

import asyncio
import logging

import anyio
import h11
from starlette.types import ASGIApp, Message, Receive, Scope, Send
from uvicorn.protocols.http.h11_impl import H11Protocol

log = logging.getLogger("bootmap.service")


def with_header_deadline(timeout_s: float) -> type[H11Protocol]:
    """uvicorn's HTTP/1.1 protocol (h11), closing a connection whose request headers take longer than
    ``timeout_s``; pass it as ``uvicorn.run(..., http=...)``."""
    return type("HeaderDeadlineProtocol", (_HeaderDeadline,), {"timeout_s": timeout_s})


class _HeaderDeadline(H11Protocol):
    timeout_s = 10.0
    _deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()  # a client that connects and sends nothing

    def data_received(self, data: bytes) -> None:
        if self._deadline is None and self.conn.their_state is h11.IDLE:
            self._arm()  # the first bytes of the next request on a kept-alive connection
        super().data_received(data)
        if self.conn.their_state is not h11.IDLE:  # the headers are in (or the connection ended)
            self._disarm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def _arm(self) -> None:
        self._disarm()
        self._deadline = self.loop.call_later(self.timeout_s, self._expired)

    def _disarm(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None

    def _expired(self) -> None:
        self._deadline = None
        if self.conn.their_state is h11.IDLE and not self.transport.is_closing():
            log.warning("a client sent no complete request headers within %g s (BOOTMAP_HEADER_TIMEOUT_S): "
                        "its connection is closed", self.timeout_s)
            self.transport.close()


class ClientStalled(BaseException):
    """Ends a response whose client stopped reading. A BaseException, like a cancellation: no error
    handler turns it into an error page (the response has started) or logs it as a bug."""


class SendTimeout:
    """Close the connection of a client that does not read its response: when one part of a response
    cannot go out within ``timeout_s`` (the client's receive window and the server's send buffer are
    full), the response ends there and uvicorn closes the connection. Without this, such a client
    would hold its connection, and the response's task, for as long as it liked."""

    def __init__(self, app: ASGIApp, timeout_s: float):
        self.app, self.timeout_s = app, timeout_s

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)

        async def timed(message: Message) -> None:
            with anyio.move_on_after(self.timeout_s) as timer:
                await send(message)
            if timer.cancelled_caught:
                log.warning("a client read nothing of its response to %s for %g s (BOOTMAP_SEND_TIMEOUT_S): "
                            "its connection is closed", scope.get("path"), self.timeout_s)
                raise ClientStalled()

        try:
            await self.app(scope, receive, timed)
        except ClientStalled:
            return  # the response is incomplete: uvicorn closes the connection
        except BaseExceptionGroup as group:  # raised inside a response's task group
            _, rest = group.split(ClientStalled)
            if rest is not None:
                raise rest
