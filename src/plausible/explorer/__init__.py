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


def create_app():
    """The FastAPI application (imported lazily: FastAPI is the ``explore`` extra)."""
    from .app import create_app as _create

    return _create()


def serve(host: str = "127.0.0.1", port: int = 8765, open_browser: bool = True) -> None:
    """Serve the explorer on ``host:port`` until interrupted (localhost by default),
    opening the page in the default browser unless ``open_browser`` is False."""
    import threading
    import webbrowser

    import uvicorn

    url = f"http://{'localhost' if host in ('127.0.0.1', '::1') else host}:{port}/"
    if open_browser:
        threading.Timer(1.0, lambda: webbrowser.open(url)).start()
    uvicorn.run(create_app(), host=host, port=port, log_level="warning")


__all__ = ["albedo", "build", "create_app", "export", "half_diff_slice", "lobe3d", "model_catalogue", "plane",
           "serve", "shader", "verdict"]
