"""The explorer's web application (FastAPI): static page plus a JSON API that
serialises :mod:`plausible.explorer.views`.  No science here.

Routes: ``GET /`` (the page), ``GET /api/models``, and ``POST`` with a JSON body
``{"model": NAME, "params": {...}, ...}`` to ``/api/validate``, ``/api/plane``,
``/api/lobe3d``, ``/api/slice``, ``/api/albedo``, ``/api/check``, ``/api/shader``
and ``/api/export``.  A parameter the model refuses is answered with status 422
and the model's own message (``{"error": "...: parameter 'nu' must lie in [0,
1e+06], got -3"}``), the same text as the Python API raises.

The rules of the server (:class:`Budget`; docs/explorer.md):

* only requests whose ``Host`` is this machine (``127.0.0.1``, ``localhost``,
  ``[::1]``, or the address it was told to bind) on the served port, and whose
  ``Origin``, when sent, is the same, are answered (403 otherwise): a web page
  on another site cannot post to the explorer, nor read its answers through a
  rebound DNS name;
* a body is at most :attr:`Budget.body_bytes` and must arrive within
  :attr:`Budget.body_seconds` (413, 408); it must be a JSON object (422);
* a request naming this machine (a loopback ``Host``) must come from this
  machine: one from another address that forges ``Host: 127.0.0.1:PORT`` is
  refused (403), which matters once ``--host`` exposes the server;
* a body nested deeper than :attr:`Budget.depth` (``[`` x 30000 fits in 64 KiB)
  is refused with 422, not a ``RecursionError``;
* the views run in one worker thread, off the event loop, one at a time (the
  computations share Dr.Jit's state); a request still running
  :attr:`Budget.seconds` after the worker took it up is stopped and answered
  503 with the budget, while the server keeps answering other requests; at
  most :attr:`Budget.queue` requests wait for it (beyond: 503 with
  ``Retry-After``);
* the cheap request (``/api/validate``: build the model, say it is valid) has
  its own lane (a second worker), so it never waits behind queued views.
"""

from __future__ import annotations

import asyncio
import ctypes
import ipaddress
import json
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles

from . import views

STATIC = Path(__file__).parent / "static"

#: Host names that always mean this machine.
LOCAL_NAMES = ("127.0.0.1", "localhost", "[::1]")


@dataclass(frozen=True)
class Budget:
    """What one request may cost (docs/explorer.md)."""

    #: Seconds of computation per request (from when the worker takes it up).
    seconds: float = 60.0
    #: Largest request body in bytes.
    body_bytes: int = 64 * 1024
    #: Seconds for the body to arrive once the headers are in.
    body_seconds: float = 10.0
    #: Seconds for a request's headers to arrive (enforced by :func:`server_config`).
    header_seconds: float = 10.0
    #: Connections served at once (beyond: 503; :func:`server_config`).
    connections: int = 64
    #: Heavy requests waiting for the worker (beyond: 503 with ``Retry-After``).
    queue: int = 8
    #: Deepest nesting of lists and objects in a request body (beyond: 422).
    depth: int = 32


class OverBudget(Exception):
    """Raised in the worker thread to stop a request over its time budget."""


class HttpError(Exception):
    def __init__(self, status: int, message: str, retry_after: float | None = None):
        super().__init__(message)
        self.status = status
        self.retry_after = retry_after


def _raise_in(thread_id: int, exc) -> None:
    """Raise ``exc`` in the thread ``thread_id`` at its next Python instruction
    (``None`` cancels one not yet raised)."""
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread_id),
                                               ctypes.py_object(exc) if exc is not None else None)


class Worker:
    """One thread that runs the views, one request at a time, off the event loop.
    A call still running after its budget is stopped by raising
    :class:`OverBudget` in that thread (a long NumPy or Dr.Jit call finishes
    first)."""

    def __init__(self, queue: int | None = None, name: str = "plausible-explorer"):
        self.pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix=name)
        self.lock = threading.Lock()
        self.current = None     # (job, thread id) while a job runs
        self.queue = queue      # most calls waiting for their turn (None: no limit)
        self.waiting = 0

    async def run(self, fn, seconds: float):
        """``fn()`` in the worker; its budget of ``seconds`` starts when it starts
        (a request waiting behind another one waits for its turn; 503 with
        ``Retry-After`` when ``queue`` requests already wait)."""
        if self.queue is not None and self.waiting >= self.queue:
            raise HttpError(503, f"{self.waiting} requests already in the worker (running or waiting; at most "
                                 f"{self.queue}): try again shortly", retry_after=max(1.0, seconds / 10))
        self.waiting += 1
        try:
            return await self._run(fn, seconds)
        finally:
            self.waiting -= 1

    async def _run(self, fn, seconds: float):
        job = object()
        loop = asyncio.get_running_loop()
        started = asyncio.Event()

        def call():
            tid = threading.get_ident()
            with self.lock:
                self.current = (job, tid)
            loop.call_soon_threadsafe(started.set)
            try:
                return fn()
            finally:
                with self.lock:
                    self.current = None
                    _raise_in(tid, None)    # a stop that came as the job ended stays unraised

        result = asyncio.wrap_future(self.pool.submit(call))
        waiting = asyncio.ensure_future(started.wait())
        await asyncio.wait({result, waiting}, return_when=asyncio.FIRST_COMPLETED)
        waiting.cancel()
        try:
            return await asyncio.wait_for(result, seconds)
        except asyncio.TimeoutError:
            with self.lock:
                if self.current is not None and self.current[0] is job:
                    _raise_in(self.current[1], OverBudget)
            raise HttpError(503, f"request over the time budget of {seconds:g} s: stopped (ask for less "
                                 f"work: a smaller 'times' or base for pumped-up, fewer lobes)") from None


def _allowed_hosts(host: str | None, port: int | None) -> set:
    names = set(LOCAL_NAMES)
    if host and host not in ("0.0.0.0", "::", ""):
        names.add(f"[{host}]" if ":" in host else host)
    return names


def _split_host(value: str) -> tuple:
    """``(name, port or None)`` of a ``Host`` value (``name``, ``name:port``, ``[v6]:port``)."""
    value = value.strip().lower()
    if value.startswith("["):
        name, _, rest = value.partition("]")
        return name + "]", (rest[1:] if rest.startswith(":") else None)
    name, _, p = value.partition(":")
    return name, (p or None)


def _is_loopback(address: str | None) -> bool:
    """Whether ``address`` (an IP address, ``[v6]`` or ``localhost``) is this machine's loopback."""
    a = (address or "").strip("[]").lower()
    if a == "localhost":
        return True
    try:
        ip = ipaddress.ip_address(a)
    except ValueError:
        return False
    return ip.is_loopback or (getattr(ip, "ipv4_mapped", None) is not None and ip.ipv4_mapped.is_loopback)


def _from_network(client) -> bool:
    """Whether the peer ``client`` (``request.client``) is another machine: an
    IP address that is not loopback (an in-process test client or a Unix socket
    has no IP address)."""
    host = getattr(client, "host", None)
    try:
        ipaddress.ip_address(host or "")
    except ValueError:
        return False
    return not _is_loopback(host)


def _host_ok(value: str, names: set, port: int | None) -> bool:
    """``value`` is ``name`` or ``name:port`` with ``name`` in ``names`` and the port the served one."""
    name, p = _split_host(value)
    if name not in names:
        return False
    if port is None:
        return p is None or p.isdigit()
    return p == str(port) or (p is None and port == 80)


def _guard(app, names, port):
    """Refuse requests to other hosts or from other origins; errors as JSON."""

    @app.middleware("http")
    async def same_origin(request: Request, call_next):
        h = request.headers.get("host", "")
        if not _host_ok(h, names, port):
            return JSONResponse({"error": f"Host {h!r} refused: the explorer answers requests to "
                                          f"{' or '.join(sorted(names))} on its own port only"}, status_code=403)
        if _is_loopback(_split_host(h)[0]) and _from_network(request.client):
            return JSONResponse({"error": f"Host {h!r} refused: it names this machine but the request comes "
                                          f"from {request.client.host}"}, status_code=403)
        origin = request.headers.get("origin")
        if origin is not None:
            scheme, _, rest = origin.partition("://")
            if scheme != "http" or not _host_ok(rest, names, port):
                return JSONResponse({"error": f"Origin {origin!r} refused: the explorer answers its own "
                                              f"page only (no cross-origin requests)"}, status_code=403)
        return await call_next(request)

    @app.exception_handler(ValueError)
    async def refused(request: Request, exc: ValueError):
        return JSONResponse({"error": str(exc)}, status_code=422)

    @app.exception_handler(HttpError)
    async def http_error(request: Request, exc: HttpError):
        headers = {"Retry-After": f"{exc.retry_after:.0f}"} if exc.retry_after else None
        return JSONResponse({"error": str(exc)}, status_code=exc.status, headers=headers)


def _check_depth(body, most: int) -> None:
    """ValueError if ``body`` nests lists or objects deeper than ``most`` (walked
    without recursion)."""
    stack = [(body, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, (list, dict)):
            if d > most:
                raise ValueError(f"request body nests lists or objects more than {most} deep")
            stack.extend((x, d + 1) for x in (v.values() if isinstance(v, dict) else v))


async def _body_of(request: Request, budget: Budget) -> dict:
    """The JSON object of the body, within the size and time ``budget``."""
    size = request.headers.get("content-length")
    if size is not None and size.isdigit() and int(size) > budget.body_bytes:
        raise HttpError(413, f"request body of {size} bytes: at most {budget.body_bytes} allowed")
    chunks, total = [], 0

    async def read():
        nonlocal total
        async for chunk in request.stream():
            total += len(chunk)
            if total > budget.body_bytes:
                raise HttpError(413, f"request body over {budget.body_bytes} bytes")
            chunks.append(chunk)

    try:
        await asyncio.wait_for(read(), budget.body_seconds)
    except asyncio.TimeoutError:
        raise HttpError(408, f"request body not received within {budget.body_seconds:g} s") from None
    try:
        body = json.loads(b"".join(chunks) or b"null")
    except (ValueError, UnicodeDecodeError) as e:
        raise ValueError(f"request body must be JSON: {e}") from None
    except RecursionError:
        raise ValueError(f"request body nests lists or objects more than {budget.depth} deep") from None
    _check_depth(body, budget.depth)
    if not isinstance(body, dict) or "model" not in body:
        raise ValueError('request body must be {"model": NAME, "params": {...}}')
    params = body.get("params")
    if params is not None and not isinstance(params, dict):
        raise ValueError(f'"params" must be an object {{"name": value, ...}}, got {type(params).__name__} '
                         f'{json.dumps(params)[:60]}')
    if not isinstance(body["model"], str):
        raise ValueError(f'"model" must be a model name (a string), got {json.dumps(body["model"])[:60]}')
    return body

def _theta(body) -> float:
    """The incidence ``theta_i`` of a request body, in degrees (default 30)."""
    t = body.get("theta_i", 30.0)
    if isinstance(t, bool) or not isinstance(t, (int, float)):
        raise ValueError(f"theta_i must be a number in [0, 90] degrees, got {json.dumps(t)[:40]}")
    if not 0.0 <= t <= 90.0:
        raise ValueError(f"theta_i must lie in [0, 90] degrees, got {t}")
    return float(t)

def _text(body, key, default) -> str:
    """The string ``body[key]`` (at most 64 characters)."""
    v = body.get(key, default)
    if not isinstance(v, str) or len(v) > 64:
        raise ValueError(f'"{key}" must be a string of at most 64 characters, got {json.dumps(v)[:40]}')
    return v


def create_app(host: str | None = None, port: int | None = None, budget: Budget = Budget()) -> FastAPI:
    """The explorer application (serve it with uvicorn; :func:`plausible.explorer.serve`).
    ``host``, ``port``: the address it is served on (``Host`` and ``Origin`` must
    name it; any port of this machine when ``port`` is None); ``budget``: the
    limits of one request (:class:`Budget`)."""
    app = FastAPI(title="plausible explorer", docs_url=None, redoc_url=None, openapi_url=None)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    catalogue = views.model_catalogue()
    worker = Worker(queue=budget.queue)
    lane = Worker(queue=budget.queue, name="plausible-explorer-cheap")     # /api/validate: never behind views
    names = _allowed_hosts(host, port)
    app.state.budget = budget

    _guard(app, names, port)

    @app.get("/")
    def index():
        return FileResponse(STATIC / "index.html")

    @app.get("/api/models")
    def models():
        return catalogue

    # the JSON views: route name -> the view of (model, request body); each runs in the worker
    routes = {
        "validate": lambda m, b: {"ok": True, "model": repr(m)},
        "plane": lambda m, b: views.plane(m, _theta(b)),
        "lobe3d": lambda m, b: views.lobe3d(m, _theta(b)),
        "slice": lambda m, b: views.half_diff_slice(m),
        "albedo": lambda m, b: views.albedo(m),
        "check": lambda m, b: views.verdict(m),
        "shader": lambda m, b: views.shader(m, prefix=_text(b, "prefix", "m0")),
    }

    async def compute(request: Request, view, on=worker):
        body = await _body_of(request, budget)
        return await on.run(lambda: view(views.build(body["model"], body.get("params") or {}), body),
                            budget.seconds)

    def route(view, on):
        async def answer(request: Request):
            return await compute(request, view, on)
        return answer

    for name, view in routes.items():
        app.post(f"/api/{name}", name=name)(route(view, lane if name == "validate" else worker))

    @app.post("/api/export")
    async def export(request: Request):
        def view(m, body):
            fmt = _text(body, "format", "spec")
            return fmt, views.export(m, fmt)

        fmt, (name, text) = await compute(request, view)
        return Response(text, media_type=views.FORMATS[fmt][1],
                        headers={"Content-Disposition": f'attachment; filename="{name}"'})

    return app


def server_config(app, host: str, port: int, budget: Budget = Budget(), **kw):
    """The uvicorn configuration of the explorer: at most ``budget.connections``
    connections (503 beyond), idle connections closed after 5 s, and a
    connection whose request headers have not all arrived within
    ``budget.header_seconds`` closed (:class:`HeaderTimeout`)."""
    import uvicorn

    return uvicorn.Config(app, host=host, port=port, log_level="warning", limit_concurrency=budget.connections,
                          timeout_keep_alive=5, http=header_timeout_protocol(budget.header_seconds), **kw)


def header_timeout_protocol(seconds: float):
    """uvicorn's h11 protocol, closing a connection that has not sent a whole
    request head within ``seconds`` of connecting or of its last response (a
    trickling client otherwise holds its socket for ever)."""
    from uvicorn.protocols.http.h11_impl import H11Protocol

    class HeaderTimeout(H11Protocol):
        _head_timer = None

        def _arm(self):
            self._armed_cycle = self.cycle
            self._head_timer = self.loop.call_later(seconds, self._head_late)

        def _head_late(self):
            self._head_timer = None
            idle = self.cycle is self._armed_cycle and (self.cycle is None or self.cycle.response_complete)
            if idle and self.transport is not None and not self.transport.is_closing():
                self.transport.close()

        def connection_made(self, transport):
            super().connection_made(transport)
            self._arm()

        def handle_events(self):
            super().handle_events()
            if self._head_timer is not None and self.cycle is not self._armed_cycle:
                self._head_timer.cancel()       # a whole request head arrived
                self._head_timer = None

        def on_response_complete(self):
            super().on_response_complete()
            if self._head_timer is None and self.transport is not None and not self.transport.is_closing():
                self._arm()                     # the next request's head on a kept-alive connection

        def connection_lost(self, exc):
            if self._head_timer is not None:
                self._head_timer.cancel()
            super().connection_lost(exc)

    return HeaderTimeout
