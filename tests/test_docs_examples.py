"""The examples of docs/fitting.md, docs/mitsuba.md, docs/export.md and docs/models/*.md run as written, on the
files shipped in docs/examples/ (written by docs/examples/make_examples.py), and
give what the docs say: the fit of the shipped samples recovers the parameters
they were made from."""

from __future__ import annotations

import ast
import importlib.util
import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from plausible.cli import main

ROOT = Path(__file__).resolve().parent.parent
DOCS = ("fitting.md", "mitsuba.md", "export.md") + tuple(
    f"models/{p.name}" for p in sorted((ROOT / "docs/models").glob("*.md")))
#: Examples that take minutes (a perceptual fit to a model target with 4 starts, a 60 s fit).
SLOW = ("--target cook-torrance", "plausible.fit(\"ashikhmin-shirley\"")


def _script():
    spec = importlib.util.spec_from_file_location("make_examples", ROOT / "docs/examples/make_examples.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _blocks(doc):
    """(language, code) of every fenced block of ``docs/doc``."""
    return re.findall(r"^```(\w*)\n(.*?)^```", (ROOT / "docs" / doc).read_text(), flags=re.S | re.M)


def _param(doc, text):
    marks = [pytest.mark.slow] if any(s in text for s in SLOW) else []
    if "mitsuba" in text:
        marks.append(pytest.mark.drjit)
    return pytest.param(text, marks=marks, id=f"{doc}:{text.splitlines()[-1][:50]}")


COMMANDS = [_param(d, ln.strip()) for d in DOCS for lang, code in _blocks(d) if lang == "sh"
            for ln in code.splitlines() if ln.strip().startswith("plausible ")]
PYTHON = [_param(d, code) for d in DOCS for lang, code in _blocks(d) if lang == "python"]


@pytest.fixture
def in_repo_copy(tmp_path, monkeypatch):
    """A working folder where ``docs/`` is the repository's (read) and outputs land in tmp."""
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_every_doc_has_examples_to_run():
    assert len(COMMANDS) >= 2 and len(PYTHON) >= 2


def test_shipped_examples_are_what_the_script_writes(tmp_path):
    _script().main([str(tmp_path)])
    assert (tmp_path / "scene.xml").read_bytes() == (ROOT / "docs/examples/scene.xml").read_bytes()
    # the samples to rounding: a formula rewritten for accuracy may move the last bit of f
    made, shipped = (np.loadtxt(d / "samples.csv", delimiter=",", skiprows=1)
                     for d in (tmp_path, ROOT / "docs/examples"))
    assert made.shape == shipped.shape and np.allclose(made, shipped, rtol=1e-12, atol=0)


@pytest.mark.parametrize("command", COMMANDS)
def test_documented_command(command, in_repo_copy):
    args = shlex.split(command, comments=True)[1:]
    r = CliRunner().invoke(main, args[:args.index(">")] if ">" in args else args)   # "> file": stdout
    assert r.exit_code == 0, r.output
    if "samples.csv" in command and shlex.split(command)[1] == "fit":   # made from kd = 0.3, ks = 0.5 (n = 20) with 2 % noise
        got = json.loads((in_repo_copy / "fit" / "fit.json").read_text())["params"]
        truth = _script().SAMPLES_TRUTH
        assert got["n"] == truth["n"]
        assert got["kd"] == pytest.approx(truth["kd"], rel=0.02) and got["ks"] == pytest.approx(truth["ks"], rel=0.02)


def _run_block(code):
    """Run a block statement by statement; the values of its expression statements, in order."""
    ns, values = {}, []
    for node in ast.parse(code).body:
        if isinstance(node, ast.Expr):
            values.append(eval(compile(ast.Expression(node.value), "<doc>", "eval"), ns))
        else:
            exec(compile(ast.Module([node], []), "<doc>", "exec"), ns)
    return ns, values


@pytest.mark.parametrize("code", PYTHON)
def test_documented_python(code, in_repo_copy):
    if "mitsuba" in code:
        pytest.importorskip("mitsuba")
    ns, values = _run_block(code)
    from plausible.fitting import FitResult

    fits = {v.target.label: v for v in values if isinstance(v, FitResult)}
    for label, res in fits.items():
        assert all(e is None or np.isfinite(e) for e in res.errors.values()), label
        if label.endswith("samples.csv"):
            assert res.params["kd"] == pytest.approx(0.3, rel=0.02) and res.params["ks"] == pytest.approx(0.5, rel=0.02)
        if label.endswith("paint.binary"):   # Ward fitted to its own MERL table (nearest-cell lookup)
            # both tangents: the pairs' half vectors turn over phi_h (alpha_y was 0.997 at phi_h = 0)
            assert res.params["alpha_x"] == pytest.approx(0.2, rel=1e-6)
            assert res.params["alpha_y"] == pytest.approx(0.2, rel=1e-6)
            assert np.allclose(res.params["rs"], 0.2, rtol=1e-6) and res.unconstrained == []
    if "img" in ns:                      # the scene renders: finite, non-negative, not blank
        img = np.asarray(ns["img"])
        assert img.shape == (64, 64, 3) and np.all(np.isfinite(img)) and img.min() >= 0 and img.std() > 0.01


def _cited(text):
    """The objects named `plausible.a.b` in ``text`` (ImportError/AttributeError if one does not exist)."""
    import importlib

    out = {}
    for name in re.findall(r"`(plausible(?:\.\w+)+)`", text):
        parts = name.split(".")
        for k in range(len(parts), 0, -1):       # the longest importable module, then attributes
            try:
                obj = importlib.import_module(".".join(parts[:k]))
            except ImportError:
                continue
            for a in parts[k:]:
                obj = getattr(obj, a)
            out[name] = obj
            break
    return out


def _export_sources_are_functions(paragraph):
    """Every name cited in the explorer's Export paragraph is a function (not a module)."""
    cited = _cited(paragraph)
    return bool(cited) and all(callable(v) for v in cited.values())


def test_the_explorer_doc_cites_functions_where_it_names_what_exports():
    import types

    text = (ROOT / "docs" / "explorer.md").read_text()
    cited = _cited(text)
    assert all(not isinstance(v, types.ModuleType) or "app" in k for k, v in cited.items()), cited
    export = re.search(r"\*\*Export\*\*.*?\n\n", text, flags=re.S).group(0)
    assert _export_sources_are_functions(export)
    assert not _export_sources_are_functions("Mitsuba 3 dict and XML element (`plausible.mitsuba.scene_dict`)")


def test_evaluate_fit_documents_what_it_returns():
    import plausible
    from plausible.fitting import evaluate_fit

    r = evaluate_fit(plausible.make("ward", alpha_x=0.2, alpha_y=0.2), "ward:alpha_x=0.25:alpha_y=0.25")
    assert set(r) == {"errors", "albedo"}
    doc = evaluate_fit.__doc__
    assert all(f'"{k}"' in doc for k in r) and all(k in doc for k in r["errors"])
