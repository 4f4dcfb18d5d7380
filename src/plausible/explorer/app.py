"""The explorer's web application (FastAPI): static page plus a JSON API that
serialises :mod:`plausible.explorer.views`.  No science here.

Routes: ``GET /`` (the page), ``GET /api/models``, and ``POST`` with a JSON body
``{"model": NAME, "params": {...}, ...}`` to ``/api/validate``, ``/api/plane``,
``/api/lobe3d``, ``/api/slice``, ``/api/albedo``, ``/api/check``, ``/api/shader``
and ``/api/export``.  A parameter the model refuses is answered with status 422
and the model's own message (``{"error": "...: parameter 'nu' must lie in [0,
1e+06], got -3"}``), the same text as the Python API raises.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles

from . import views

STATIC = Path(__file__).parent / "static"


def create_app() -> FastAPI:
    """The explorer application (serve it with uvicorn; :func:`plausible.explorer.serve`)."""
    app = FastAPI(title="plausible explorer", docs_url=None, redoc_url=None, openapi_url=None)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    catalogue = views.model_catalogue()

    @app.exception_handler(ValueError)
    async def refused(request: Request, exc: ValueError):
        return JSONResponse({"error": str(exc)}, status_code=422)

    @app.get("/")
    def index():
        return FileResponse(STATIC / "index.html")

    @app.get("/api/models")
    def models():
        return catalogue

    async def model_of(request: Request):
        body = await request.json()
        if not isinstance(body, dict) or "model" not in body:
            raise ValueError('request body must be {"model": NAME, "params": {...}}')
        return views.build(str(body["model"]), body.get("params") or {}), body

    def _theta(body):
        t = float(body.get("theta_i", 30.0))
        if not 0.0 <= t <= 90.0:
            raise ValueError(f"theta_i must lie in [0, 90] degrees, got {t}")
        return t

    # the JSON views: route name -> the view of (model, request body); requests run one at a
    # time on the event loop (the computations share Dr.Jit's state, which is not for threads)
    routes = {
        "validate": lambda m, b: {"ok": True, "model": repr(m)},
        "plane": lambda m, b: views.plane(m, _theta(b)),
        "lobe3d": lambda m, b: views.lobe3d(m, _theta(b)),
        "slice": lambda m, b: views.half_diff_slice(m),
        "albedo": lambda m, b: views.albedo(m),
        "check": lambda m, b: views.verdict(m),
        "shader": lambda m, b: views.shader(m, prefix=str(b.get("prefix", "m0"))),
    }

    def route(view):
        async def answer(request: Request):
            return view(*await model_of(request))
        return answer

    for name, view in routes.items():
        app.post(f"/api/{name}", name=name)(route(view))

    @app.post("/api/export")
    async def export(request: Request):
        m, body = await model_of(request)
        name, text = views.export(m, str(body.get("format", "spec")))
        mime = views.FORMATS[str(body.get("format", "spec"))][1]
        return Response(text, media_type=mime,
                        headers={"Content-Disposition": f'attachment; filename="{name}"'})

    return app
