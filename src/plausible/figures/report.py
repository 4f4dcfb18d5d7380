"""The figures report: run every figure (progress bar, cache) and write ``index.html``.

Cache: each figure's directory ``OUT/NAME/`` holds ``figure.json`` with the hash
of its inputs (figure name, parameters, resolution, spp, quick mode, and the
source of the plausible package except the CLI and this runner).  A figure
whose hash and files are unchanged is not made again.

A figure is made in a temporary folder ``OUT/.NAME.partial-*`` and put in place
of ``OUT/NAME/`` by renaming it only when it is complete, so ``OUT/NAME/`` always
holds the files of one run, the run its ``figure.json`` describes: a run
interrupted (Ctrl-C) or killed while it remakes a figure leaves the previous
one as it was, and the cache never claims files of another run.  On any exit,
Ctrl-C included, ``index.html`` is written for the figures made so far.
"""

from __future__ import annotations

import hashlib
import html
import json
import os
import shutil
import tempfile
import time
import traceback
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from ..progress import start
from ..text import fmt
from .core import FIGURES, Context, get, names

_PKG = Path(__file__).resolve().parent.parent


def source_hash() -> str:
    """SHA-1 over the package's sources that figures depend on."""
    h = hashlib.sha1()
    for p in sorted(_PKG.rglob("*")):
        if p.suffix not in (".py", ".csv") or p.name in ("cli.py", "report.py") or "__pycache__" in p.parts:
            continue
        h.update(str(p.relative_to(_PKG)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def input_key(fig, *, resolution, spp, quick, src=None) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("plausible")
    except PackageNotFoundError:   # pragma: no cover
        ver = "0"
    blob = json.dumps(dict(name=fig.name, params=fig.params, resolution=resolution, spp=spp, quick=quick,
                           version=ver, source=src or source_hash()), sort_keys=True, default=str)
    return hashlib.sha1(blob.encode()).hexdigest()


def _cached(d: Path, key: str):
    meta = d / "figure.json"
    if not meta.exists():
        return None
    try:
        m = json.loads(meta.read_text())
    except ValueError:
        return None
    if m.get("key") != key or m.get("status") != "ok":
        return None
    files = [it.get("png") or it.get("file") for it in m.get("items", [])]
    files += [it["exr"] for it in m.get("items", []) if it.get("exr")]
    return m if all((d / f).exists() for f in files) else None


def _remove_partial(out: Path, name: str):
    for p in list(out.glob(f".{name}.partial-*")) + list(out.glob(f".{name}.old-*")):
        shutil.rmtree(p, ignore_errors=True)


def _replace(tmp: Path, d: Path):
    """Put the finished figure folder ``tmp`` in place of ``d`` (renames only; the
    old folder is moved aside first, since a rename cannot replace a non-empty one)."""
    old = None
    if d.exists():
        old = d.with_name(f".{d.name}.old-{os.getpid()}")
        d.rename(old)
    tmp.rename(d)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _index_all(out: Path, results: dict) -> Path:
    """``index.html`` of every figure present in ``out``, not only this run's."""
    allm = {}
    for n in names():
        if n in results:
            allm[n] = results[n]
        elif (out / n / "figure.json").exists():
            try:
                allm[n] = json.loads((out / n / "figure.json").read_text())
            except ValueError:
                pass
    return write_index(out, allm)


def _dir_mode() -> int:
    """The mode ``mkdir`` gives a new folder under the current umask (0755 under 022)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o777 & ~mask


def run(out, *, only=None, spp=None, resolution=None, quick=False, force=False, console=None,
        progress=None) -> dict:
    """Make the figures (all, or the names in ``only``) into ``out`` and write
    ``out/index.html``.  Returns ``{name: figure.json contents}``; each has
    ``status`` ("ok" or "failed"), ``cached`` and ``seconds``.

    ``spp`` / ``resolution`` override the samples per pixel / base image size
    (defaults :data:`plausible.figures.DEFAULT_SPP` / ``DEFAULT_RESOLUTION``);
    ``quick`` uses small ones (the CI mode).  Deterministic: fixed seeds.
    ``progress``: a :mod:`plausible.progress` factory, announced once per figure
    (labelled with its name); a line per figure says how it went.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    console = console or Console()
    todo = names() if not only else list(dict.fromkeys(get(n).name for n in only))
    src = source_hash()
    results = {}
    t_all = time.time()
    tmp, name = None, ""
    try:
        for name in todo:
            fig = FIGURES[name]
            d = out / name
            key = input_key(fig, resolution=resolution, spp=spp, quick=quick, src=src)
            m = None if force else _cached(d, key)
            if m is not None:
                m["cached"] = True
                console.print(f"{escape(name):<22} cached")
                results[name] = m
                continue
            _remove_partial(out, name)      # left by a run that was killed
            tmp = Path(tempfile.mkdtemp(prefix=f".{name}.partial-", dir=out))
            os.chmod(tmp, _dir_mode())      # mkdtemp makes 0700: the figure folder follows the umask
            ctx = Context(tmp, resolution=resolution, spp=spp, quick=quick,
                          progress=lambda total, label="", _n=name: start(progress, total, _n))
            t0 = time.time()
            m = dict(name=name, title=fig.title, source=fig.source, caption=fig.caption, params=fig.params,
                     key=key, resolution=ctx.base_res, spp=ctx.base_spp, quick=quick, renders=fig.renders)
            try:
                fig.fn(ctx, **fig.params)
                m["status"] = "ok"
            except Exception:   # a failing figure is reported, the others still run
                m["status"] = "failed"
                m["error"] = traceback.format_exc()
                console.print(f"[red]figure {escape(name)} failed:[/red]\n{escape(m['error'])}")
            ctx.finish()
            m.update(items=ctx.items, measurements=ctx.measurements, notes=ctx.notes,
                     seconds=round(time.time() - t0, 1), cached=False)
            (tmp / "figure.json").write_text(json.dumps(m, indent=1))
            _replace(tmp, d)
            tmp = None
            console.print(f"{escape(name):<22} {m['status']} {m['seconds']} s")
            results[name] = m
    except KeyboardInterrupt:
        console.print(f"[yellow]interrupted while making {escape(name)}: it is left as it was before "
                      f"this run; {len(results)} figures done -> {escape(str(out / 'index.html'))}[/yellow]")
        raise
    finally:    # on any exit: drop the unfinished figure, index what is done
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
        _index_all(out, results)
    total = round(time.time() - t_all, 1)
    failed = [n for n, m in results.items() if m["status"] != "ok"]
    checks = [x for m in results.values() for x in m.get("measurements", []) if "ok" in x]
    bad = [x for x in checks if not x["ok"]]
    console.print(f"{len(results)} figures ({sum(m.get('cached', False) for m in results.values())} cached, "
                  f"{len(failed)} failed) in {total} s; {len(checks) - len(bad)}/{len(checks)} measured "
                  f"checks hold -> {escape(str(out / 'index.html'))}")
    return results


# -- index.html ---------------------------------------------------------------------

_CSS = """body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h2{border-top:1px solid #ccc;padding-top:1em}figure{display:inline-block;margin:.5em;vertical-align:top}
figure img{max-width:520px;image-rendering:pixelated;border:1px solid #ddd}figcaption{font-size:.85em;max-width:520px}
blockquote{color:#444;border-left:3px solid #aaa;margin:.5em 0;padding-left:1em}table{border-collapse:collapse;font-size:.9em}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}.ok{color:#080}.bad{color:#b00;font-weight:bold}
.failed{background:#fee;padding:1em}nav a{margin-right:.8em}code{font-size:.9em}"""

#: Sets ``data-images`` on <body> to "LOADED/TOTAL" once every image has loaded or
#: failed (the headless-browser test reads it); broken images get a red border.
_JS = """<script>
(function(){
  function done(){
    var imgs=document.images, ok=0, n=imgs.length, pending=0;
    for(var i=0;i<n;i++){ if(!imgs[i].complete){pending++;} else if(imgs[i].naturalWidth>0){ok++;}
      else {imgs[i].style.border='3px solid red';} }
    if(pending>0){ setTimeout(done, 50); return; }
    document.body.setAttribute('data-images', ok+'/'+n);
  }
  window.addEventListener('load', done);
})();
</script>"""


def _cell(x):
    """A measurement's number (a boolean as yes / no) in a table cell."""
    if isinstance(x, bool):
        return "yes" if x else "no"
    return "" if x is None else html.escape(fmt(x, ".6g"))


def _expected(x) -> str:
    """The "expected" cell: the value, or the bounds ``>= a`` / ``<= b``."""
    bounds = [f"&ge; {_cell(x['at_least'])}" if x.get("at_least") is not None else "",
              f"&le; {_cell(x['at_most'])}" if x.get("at_most") is not None else ""]
    bounds = [b for b in bounds if b]
    if bounds:
        return ", ".join(bounds)
    return _cell(x.get("expected"))


def write_index(out: Path, figs: dict) -> Path:
    """Write ``out/index.html`` showing every figure in ``figs`` (``figure.json`` contents)."""
    e = html.escape
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>plausible: the papers' figures</title>",
             f"<style>{_CSS}</style>{_JS}</head><body>",
             "<h1>plausible: the papers' figures, reproduced</h1>",
             "<p>Each section shows a figure of Ashikhmin &amp; Shirley (2000), Neumann, Neumann &amp; "
             "Szirmay-Kalos (1999) or the Modified Phong notes, with the paper's caption, the parameters used, "
             "and the numbers measured on it (checks in <span class='ok'>green</span> hold, "
             "<span class='bad'>red</span> do not). Renders: PNG for viewing (sRGB, clipped at 1), EXR for "
             "the linear radiance. Made by <code>plausible figures</code>.</p><nav>"]
    parts += [f"<a href='#{e(n)}'>{e(n)}</a>" for n in figs]
    parts.append("</nav>")
    for n, m in figs.items():
        parts.append(f"<h2 id='{e(n)}'>{e(m.get('title', n))}</h2>")
        parts.append(f"<p><b>{e(m.get('source', ''))}</b></p><blockquote>{e(m.get('caption', ''))}</blockquote>")
        params = dict(m.get("params", {}))
        if m.get("renders", True):   # image size and samples only where the section renders
            params.update(resolution=m.get("resolution"), spp=m.get("spp"))
        parts.append("<p>Parameters: " + ", ".join(f"<code>{e(k)} = {e(str(v))}</code>" for k, v in params.items())
                     + f" &middot; made in {m.get('seconds', '?')} s</p>")
        if m.get("status") != "ok":
            parts.append(f"<pre class='failed'>{e(m.get('error', 'failed'))}</pre>")
        for it in m.get("items", []):
            if it["kind"] in ("image", "plot"):
                link = f" &middot; <a href='{e(n)}/{e(it['exr'])}'>EXR</a>" if it.get("exr") else ""
                parts.append(f"<figure><a href='{e(n)}/{e(it['png'])}'><img src='{e(n)}/{e(it['png'])}' "
                             f"alt='{e(it['png'])}'></a><figcaption>{e(it.get('caption', ''))}{link}"
                             "</figcaption></figure>")
        data = [it for it in m.get("items", []) if it["kind"] == "data"]
        if data:
            parts.append("<p>Data: " + ", ".join(f"<a href='{e(n)}/{e(it['file'])}'>{e(it['file'])}</a>"
                                                 + (f" ({e(it['caption'])})" if it.get("caption") else "")
                                                 for it in data) + "</p>")
        meas = m.get("measurements", [])
        if meas:
            parts.append("<table><tr><th>measured</th><th>value</th><th>expected</th><th>tolerance</th>"
                         "<th></th><th>note</th></tr>")
            for x in meas:
                ok = x.get("ok")
                cls = "" if ok is None else ("ok" if ok else "bad")
                verdict = "" if ok is None else ("holds" if ok else "DOES NOT HOLD")
                parts.append(f"<tr><td>{e(x['quantity'])}</td><td>{_cell(x['measured'])}</td>"
                             f"<td>{_expected(x)}</td><td>{_cell(x['tol'])}</td>"
                             f"<td class='{cls}'>{verdict}</td><td>{e(x.get('note', ''))}</td></tr>")
            parts.append("</table>")
        for t in m.get("notes", []):
            parts.append(f"<p>{e(t)}</p>")
    parts.append("</body></html>")
    path = out / "index.html"
    path.write_text("\n".join(parts))
    return path
