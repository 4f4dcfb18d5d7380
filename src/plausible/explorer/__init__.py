"""``plausible explore``: an interactive BRDF explorer in the browser.

A local web application (FastAPI, served by uvicorn on 127.0.0.1) over the
library: every registered model with sliders generated from its parameter
specs; a lit sphere drawn in WebGL2 by the model's exported GLSL
(:mod:`plausible.export`); the lobe in the plane of incidence, the 3-D lobe,
the directional albedo with its error bound and the ``theta_h x theta_d``
slice (:mod:`plausible.explorer.views`); the plausibility verdict of
:func:`plausible.check`; exports as spec, Mitsuba dict and XML, GLSL and BRDF
Explorer file.  See docs/explorer.md.
"""

from __future__ import annotations

from .views import (albedo, build, export, half_diff_slice, lobe3d, model_catalogue, plane, shader,
                    verdict)


def create_app(host=None, port=None):
    """The FastAPI application (imported lazily: FastAPI is the ``explore`` extra);
    ``host``, ``port``: the address served (see :func:`plausible.explorer.app.create_app`)."""
    from .app import create_app as _create

    return _create(host, port)


def resolve_host(host: str | None) -> tuple:
    """``(address to bind, exposed)`` for the ``--host`` a user gave: an empty
    or missing host binds the loopback ``127.0.0.1``; ``exposed`` is True only
    when the user named an address other machines can reach (``0.0.0.0``,
    ``::``, a LAN address, a host name that is not ``localhost``), and then
    whoever serves must say so loudly (the CLI does)."""
    from .app import _is_loopback

    host = (host or "").strip()
    if not host:
        return "127.0.0.1", False
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    return host, not _is_loopback(host)


def bind(host: str = "127.0.0.1", port: int = 8765):
    """A listening socket on ``host:port`` (as uvicorn binds it), or ValueError
    saying the port is taken: bound *before* the URL is announced, so a busy
    port is a clear message, not an announced URL followed by ``Errno 98``."""
    import socket

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
        sock.listen(2048)
    except OSError as e:
        sock.close()
        if isinstance(e, socket.gaierror):      # the host is no name or address of this machine
            raise ValueError(f"cannot listen on {host}:{port}: {e.strerror} (host: give a name or address of "
                             f"this machine, such as 127.0.0.1 or 0.0.0.0)") from None
        raise ValueError(f"cannot listen on {host}:{port}: {e.strerror} (another program, or another "
                         f"explorer, may hold the port: choose another port)") from None
    sock.set_inheritable(True)
    return sock


def url_of(host: str, port: int) -> str:
    """The URL to open for a server bound to ``host:port`` (``localhost`` for
    loopback or an empty host, brackets around an IPv6 address)."""
    host = (host or "").strip("[]")
    if host in ("", "127.0.0.1", "::1", "0.0.0.0", "::"):
        host = "localhost"
    return f"http://{f'[{host}]' if ':' in host else host}:{port}/"


def serve(host: str = "127.0.0.1", port: int = 8765, open_browser: bool = True, sock=None) -> None:
    """Serve the explorer on ``host:port`` until interrupted (localhost by default),
    opening the page in the default browser unless ``open_browser`` is False.
    ``sock``: a socket from :func:`bind` (else one is bound here)."""
    import threading
    import webbrowser

    import uvicorn

    host, _ = resolve_host(host)
    sock = sock if sock is not None else bind(host, port)
    if open_browser:
        threading.Timer(1.0, lambda: webbrowser.open(url_of(host, port))).start()
    from .app import server_config

    server = uvicorn.Server(server_config(create_app(host, port), host, port))
    server.run(sockets=[sock])


__all__ = ["albedo", "bind", "build", "create_app", "export", "half_diff_slice", "lobe3d", "model_catalogue", "plane",
           "resolve_host", "serve", "shader", "url_of", "verdict"]
