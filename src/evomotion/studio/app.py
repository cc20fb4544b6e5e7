"""``evomotion studio``: the web app over a folder of runs (NiceGUI: Vue/Quasar, ECharts and
three.js ship with it; nothing of a front end is kept in this repository).

Security: the server binds 127.0.0.1 unless ``--host`` says otherwise (and then warns). A token
is made at start and printed with the URL, as Jupyter does; every page and file request needs
it (the first visit carries it in the URL, which sets a same-site cookie), and every request
that changes anything (the ``/api`` routes) needs it in the ``X-Evomotion-Token`` header, so a
page of another site in the same browser can neither read runs nor start or stop them. Files
are served only from below RUNS_DIR (:func:`~evomotion.studio.data.safe_file`).
"""

from __future__ import annotations

import hmac
import secrets
import sys
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.studio.readers import one_line

COOKIE = "evomotion_token"
HEADER = "X-Evomotion-Token"
LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")
#: NiceGUI's own assets and websocket (library files, nothing of RUNS_DIR)
OPEN_PREFIXES = ("/_nicegui", "/favicon.ico")


def _same(a: str | None, b: str) -> bool:
    return a is not None and hmac.compare_digest(a.encode(), b.encode())


def install_security(app: Any, token: str) -> None:
    """The token check in front of every route but NiceGUI's static assets."""
    from starlette.middleware.base import BaseHTTPMiddleware
    from starlette.responses import PlainTextResponse

    async def dispatch(request, call_next):
        path = request.url.path
        if path.startswith(OPEN_PREFIXES):
            return await call_next(request)
        if path.startswith("/api/"):
            if not _same(request.headers.get(HEADER), token):
                return PlainTextResponse(f"403: {HEADER} header missing or wrong", 403)
            return await call_next(request)
        from_query = _same(request.query_params.get("token"), token)
        if not (from_query or _same(request.cookies.get(COOKIE), token)):
            return PlainTextResponse("403: open the URL with the token that "
                                     "'evomotion studio' printed", 403)
        response = await call_next(request)
        if from_query:
            response.set_cookie(COOKIE, token, httponly=True, samesite="strict")
        return response

    app.add_middleware(BaseHTTPMiddleware, dispatch=dispatch)


def add_api(app: Any, root: Path) -> None:
    """JSON routes for scripts and for the page's own buttons' fallback; token-checked."""
    from fastapi import Body
    from fastapi.responses import FileResponse, JSONResponse, PlainTextResponse

    from evomotion.studio import actions, data

    def fail(e: Exception) -> Any:
        return JSONResponse({"error": str(e)}, 400)

    from fastapi.exception_handlers import request_validation_exception_handler
    from fastapi.exceptions import RequestValidationError

    @app.exception_handler(RequestValidationError)
    async def bad_parameters(request, exc):
        # a missing or mistyped query parameter of an /api route (``generations=ten``): one
        # line and 400, as every other refusal, not FastAPI's 422 document
        if not request.url.path.startswith("/api/"):
            return await request_validation_exception_handler(request, exc)
        return JSONResponse({"error": validation_line(exc.errors())}, 400)

    @app.get("/files")
    def files(path: str, download: int = 0):
        try:
            found = data.safe_file(root, path)
            # download=1: saved under its own name (Content-Disposition: attachment)
            return FileResponse(found, filename=found.name if download else None)
        except InputError as e:
            return PlainTextResponse(str(e), 404)

    @app.get("/api/runs")
    def runs(study: str = ""):
        return [r.row() for r in data.list_runs(root, study or None)]

    @app.post("/api/stop")
    def stop(name: str):
        try:
            return {"stopped": actions.stop_run(root, name)}
        except InputError as e:
            return fail(e)

    @app.post("/api/resume")
    def resume(name: str):
        try:
            return {"pid": actions.resume_run(root, name).pid}
        except InputError as e:
            return fail(e)

    @app.post("/api/extend")
    def extend(name: str, generations: int):
        try:
            return {"pid": actions.extend_run(root, name, generations).pid}
        except InputError as e:
            return fail(e)

    @app.post("/api/start")
    def start(body: Any = Body(None)):  # noqa: B008 - FastAPI's way to take a JSON body
        # ``Any`` (a name in this module's globals) rather than ``Request`` imported here:
        # under ``from __future__ import annotations`` FastAPI resolves the annotation from
        # the globals, and a local ``Request`` made ``request`` a query parameter (every POST
        # answered 422; issue 35)
        try:
            study, preset, sets, name, tags = _start_body(body)
            out, proc = actions.start_run(root, study, preset, sets, name, tags)
        except InputError as e:
            return fail(e)
        return {"name": out.relative_to(root).as_posix(), "pid": proc.pid}


def validation_line(errors: Any) -> str:
    """FastAPI's validation errors as one line: ``generations: expected a valid integer,
    got 'ten'`` (the first four, joined by '; ')."""
    parts = []
    for e in list(errors)[:4]:
        loc = e.get("loc") or ("?",)
        what = str(e.get("msg", "invalid")).replace("Input should be", "expected")
        got = "" if e.get("type") == "missing" else f", got {one_line(repr(e.get('input')), 60)}"
        parts.append(f"{loc[-1]}: {one_line(what, 120)}{got}")
    return "; ".join(parts) or "invalid parameters"


def _start_body(body: Any) -> tuple[str, str | None, list[str], str, tuple[str, ...]]:
    """(study, preset, sets, name, tags) of a ``/api/start`` JSON body, or one-line
    :class:`InputError`."""
    from evomotion.studio.tags import check_tags

    if not isinstance(body, dict):
        raise InputError("expected a JSON object {\"study\": ..., \"preset\": ..., "
                         "\"sets\": [...], \"name\": ..., \"tags\": [...]}")
    tags = check_tags(body.get("tags") or [])
    study, preset, sets = body.get("study"), body.get("preset"), body.get("sets", [])
    name = body.get("name") or ""
    if not isinstance(name, str):
        raise InputError("name: expected a run name (a string) or null")
    if not isinstance(study, str):
        raise InputError("study: expected a study name (a string)")
    if preset is not None and not isinstance(preset, str):
        raise InputError("preset: expected a name or null")
    if not isinstance(sets, list) or not all(isinstance(x, str) for x in sets):
        raise InputError("sets: expected a list of 'key=value' strings")
    return study, preset, sets, name, tags


def serve(root: Path, host: str = "127.0.0.1", port: int = 8765,
          token: str | None = None) -> None:
    """Build the pages and serve until Ctrl-C."""
    from nicegui import app, ui

    from evomotion.studio import pages

    root = Path(root)
    if not root.is_dir():
        raise InputError(f"{root}: no such folder of runs")
    token = token or secrets.token_urlsafe(24)
    if host not in LOCAL_HOSTS:
        print(f"warning: the studio listens on {host}, reachable from other machines; "
              "anyone with the token can start and stop runs", file=sys.stderr)
    install_security(app, token)
    add_api(app, root.resolve())
    pages.build(root.resolve())
    shown = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    print(f"evomotion studio over {root}: http://{shown}:{port}/?token={token}", flush=True)
    ui.run(host=host, port=port, reload=False, show=False, title="evomotion studio",
           show_welcome_message=False, uvicorn_logging_level="warning", favicon="🤖")
