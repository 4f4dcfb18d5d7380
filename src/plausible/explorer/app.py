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

    @app.post("/api/validate")
    async def validate(request: Request):
        m, _ = await model_of(request)
        return {"ok": True, "model": repr(m)}

    @app.post("/api/plane")
    async def plane(request: Request):
        m, body = await model_of(request)
        return views.plane(m, _theta(body))

    @app.post("/api/lobe3d")
    async def lobe3d(request: Request):
        m, body = await model_of(request)
        return views.lobe3d(m, _theta(body))

    @app.post("/api/slice")
    async def slice_(request: Request):
        m, _ = await model_of(request)
        return views.half_diff_slice(m)

    @app.post("/api/albedo")
    async def albedo(request: Request):
        m, _ = await model_of(request)
        return views.albedo(m)

    @app.post("/api/check")
    async def check(request: Request):
        m, _ = await model_of(request)
        return views.verdict(m)

    @app.post("/api/shader")
    async def shader(request: Request):
        m, body = await model_of(request)
        return views.shader(m, prefix=str(body.get("prefix", "m0")))

    @app.post("/api/export")
    async def export(request: Request):
        m, body = await model_of(request)
        name, text = views.export(m, str(body.get("format", "spec")))
        mime = views.FORMATS[str(body.get("format", "spec"))][1]
        return Response(text, media_type=mime,
                        headers={"Content-Disposition": f'attachment; filename="{name}"'})

    return app
