"""The exported GLSL through the Khronos reference compiler (``glslangValidator``,
Debian's ``glslang-tools``; ``make glslang`` installs it): two exports in one
shader, the precision every exported operation gets under a ``mediump``
default, and the ``.brdf`` code as BRDF Explorer compiles it (``#version 410``).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess

import pytest
from click.testing import CliRunner

import brdf_file
import plausible
from plausible.cli import main
from plausible.export import to_brdf, to_glsl


@pytest.fixture(scope="module")
def glslang():
    exe = shutil.which("glslangValidator")
    if exe is None:
        if os.environ.get("CI"):
            pytest.fail("glslangValidator is missing (make glslang installs Debian's glslang-tools)")
        pytest.skip("glslangValidator is not installed (make glslang installs Debian's glslang-tools)")
    return exe


def compile_glsl(exe, tmp_path, source, stage="frag", ast=False):
    """``(ok, output)`` of glslangValidator on ``source`` (with ``ast``: the
    intermediate tree, every node with its precision)."""
    path = tmp_path / f"shader.{stage}"
    path.write_text(source)
    r = subprocess.run([exe, *(["-i"] if ast else []), str(path)], capture_output=True, text=True, timeout=60)
    return r.returncode == 0, r.stdout + r.stderr


ES_HEADER = "#version 300 es\nprecision mediump float;\nin vec3 vwi;\nin vec3 vwo;\nout vec4 color;\n"


def test_two_prefixed_cli_exports_compile_in_one_shader(glslang, tmp_path):
    """Two files from ``plausible export --prefix`` pasted into one fragment shader:
    each helper defined once (guarded), both models callable; the same two with
    one prefix fail (the check can fail)."""
    def export(args, name):
        r = CliRunner().invoke(main, ["export", *args, "--out", str(tmp_path / name)])
        assert r.exit_code == 0, r.output
        return (tmp_path / name).read_text()

    a = export(["ashikhmin-shirley", "--uniforms", "--prefix", "as"], "as.glsl")
    b = export(["lafortune", "--prefix", "laf"], "laf.glsl")   # both use plausible_pow and its log1p
    assert "plausible_pow" in a and "plausible_pow" in b
    body = ("void main() { vec3 w; float p; vec3 d = laf_sample(vwi, vwo, w, p);\n"
            "  color = vec4(as_f(vwi, vwo) + laf_f(vwi, vwo) + w * as_pdf(vwi, d), p); }\n")
    ok, log = compile_glsl(glslang, tmp_path, ES_HEADER + a + b + body)
    assert ok, log
    same = export(["lafortune", "--prefix", "as"], "as2.glsl")
    ok, log = compile_glsl(glslang, tmp_path, ES_HEADER + a + same + body.replace("laf_", "as_"))
    assert not ok and "already has a body" in log


def _functions(tree: str) -> dict:
    """The intermediate tree of glslangValidator -i, split per function definition."""
    parts = re.split(r"^0:\S+\s+Function Definition: ", tree, flags=re.M)
    return {p.split("(")[0]: p for p in parts[1:]}


def lower_precision_nodes(tree: str) -> dict:
    """Per exported function (all but ``main``), the nodes of its tree that are
    ``mediump`` or ``lowp``."""
    return {name: n for name, text in _functions(tree).items() if name != "main"
            and (n := len(re.findall(r"\b(?:mediump|lowp)\b", text)))}


@pytest.mark.parametrize("name", plausible.names())
def test_the_export_computes_in_highp_under_a_mediump_default(glslang, tmp_path, name):
    """Guards of 1e-12 and exponents of 1e4 need float32: every value the exported
    functions compute is highp although the host's default is mediump (mediump
    may be 16 bits: largest 65504, smallest normal 6e-5)."""
    s = to_glsl(plausible.make(name), uniforms=True)
    call = "plausible_f(vwi, vwo)" + (" * plausible_pdf(vwi, vwo)" if s.sampling else "")
    src = ES_HEADER + s.text + f"void main() {{ color = vec4({call}, 1.0); }}\n"
    ok, tree = compile_glsl(glslang, tmp_path, src, ast=True)
    assert ok, tree
    funcs = _functions(tree)
    assert "plausible_f" in funcs and lower_precision_nodes(tree) == {}


def test_the_precision_check_finds_mediump(glslang, tmp_path):
    s = to_glsl(plausible.make("reciprocal-phong"), uniforms=True)
    src = ES_HEADER + s.text.replace("highp ", "") + "void main() { color = vec4(plausible_f(vwi, vwo), 1.0); }\n"
    ok, tree = compile_glsl(glslang, tmp_path, src, ast=True)
    assert ok and lower_precision_nodes(tree).get("plausible_f", 0) > 10


@pytest.mark.parametrize("name", plausible.names())
def test_brdf_files_compile_as_the_explorer_compiles_them(glslang, tmp_path, name):
    """BRDF Explorer prepends ``#version 410`` and the parameters' uniforms to the
    shader section (and its templates' own code, here a main calling BRDF)."""
    parsed = brdf_file.parse(to_brdf(plausible.make(name)))
    src = ("#version 410\n" + brdf_file.uniforms(parsed) + parsed["sections"]["shader"]
           + parsed["sections"].get("isFunc", "")
           + "in vec3 L; in vec3 V;\nout vec4 color;\n"
           + "void main() { color = vec4(BRDF(L, V, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), "
             "vec3(0.0, 1.0, 0.0)), 1.0); }\n")
    ok, log = compile_glsl(glslang, tmp_path, src)
    assert ok, log
