"""Run fragment shaders in headless Chromium (WebGL2 on SwiftShader) and read
their float results back: the harness of the GLSL export tests.

One browser page serves every shader of a test session.  Each run draws a
``W x H`` float render target (``RGBA32F``, ``EXT_color_buffer_float``); the
inputs are ``RGBA32F`` textures read with ``texelFetch`` at the pixel's own
index, so input row ``k`` and output row ``k`` are the same direction pair.
"""

from __future__ import annotations

import base64
import shutil

import numpy as np

WIDTH = 64

CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox",
                 "--headless=new", "--disable-background-networking", "--disable-extensions",
                 "--disable-sync", "--no-first-run", "--mute-audio"]

_PAGE = """<!doctype html><html><body><canvas id="c" width="1" height="1"></canvas><script>
const gl = document.getElementById('c').getContext('webgl2');
const ext = gl && gl.getExtension('EXT_color_buffer_float');
window.ready = !!(gl && ext);
function b64f(s) { const b = atob(s); const u = new Uint8Array(b.length);
  for (let i = 0; i < b.length; i++) u[i] = b.charCodeAt(i); return new Float32Array(u.buffer); }
function f64b(a) { const u = new Uint8Array(a.buffer); let s = '';
  for (let i = 0; i < u.length; i += 8192) s += String.fromCharCode.apply(null, u.subarray(i, i + 8192));
  return btoa(s); }
const VS = `#version 300 es
void main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }`;
function compile(type, src) { const s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('compile: ' + gl.getShaderInfoLog(s));
  return s; }
let inputs = [];
window.setInputs = function(list, w, h) {
  inputs.forEach(t => gl.deleteTexture(t));
  inputs = list.map(s => { const t = gl.createTexture(); gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, b64f(s)); return t; });
  return inputs.length;
};
window.runMany = function(jobs, w, h) {
  const fb = gl.createFramebuffer(); const tex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, tex);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, null);
  gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
  const vs = compile(gl.VERTEX_SHADER, VS);
  const out = [];
  for (const job of jobs) {
    try {
      const fs = compile(gl.FRAGMENT_SHADER, job.src);
      const prog = gl.createProgram(); gl.attachShader(prog, vs); gl.attachShader(prog, fs);
      gl.linkProgram(prog);
      if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error('link: ' + gl.getProgramInfoLog(prog));
      gl.useProgram(prog);
      inputs.forEach((t, i) => { gl.activeTexture(gl.TEXTURE0 + i); gl.bindTexture(gl.TEXTURE_2D, t);
        gl.uniform1i(gl.getUniformLocation(prog, 'in' + i), i); });
      for (const [name, v] of Object.entries(job.uniforms)) {
        const loc = gl.getUniformLocation(prog, name);
        if (v.length == 3) gl.uniform3f(loc, v[0], v[1], v[2]); else gl.uniform1f(loc, v[0]);
      }
      gl.viewport(0, 0, w, h); gl.drawArrays(gl.TRIANGLES, 0, 3);
      const px = new Float32Array(w * h * 4);
      gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, px);
      gl.deleteProgram(prog); gl.deleteShader(fs);
      out.push({ok: true, data: f64b(px)});
    } catch (e) { out.push({ok: false, error: String(e)}); }
  }
  gl.deleteFramebuffer(fb); gl.deleteTexture(tex);
  return out;
};
</script></body></html>"""

HEADER = """#version 300 es
precision highp float;
precision highp int;
uniform highp sampler2D in0;
uniform highp sampler2D in1;
uniform highp sampler2D in2;
out vec4 outColor;
"""

MAIN = """
void main()
{
    ivec2 ij = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(in0, ij, 0);
    vec4 b = texelFetch(in1, ij, 0);
    vec4 c = texelFetch(in2, ij, 0);
    %s
}
"""


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


class Browser:
    """A headless Chromium page with WebGL2; :meth:`run` evaluates shaders."""

    def __init__(self):
        from playwright.sync_api import sync_playwright

        self._pw = sync_playwright().start()
        try:
            self._browser = self._pw.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
            self.page = self._browser.new_page()
            self.page.set_content(_PAGE)
            self.ready = bool(self.page.evaluate("window.ready"))
        except Exception:
            self._pw.stop()
            raise

    def close(self):
        self._browser.close()
        self._pw.stop()

    def set_inputs(self, arrays):
        """Up to three ``(N, 3 or 4)`` float arrays (``N`` a multiple of ``WIDTH``),
        read in the shader as ``a``, ``b``, ``c`` (``vec4``)."""
        n = len(arrays[0])
        if n % WIDTH:
            raise ValueError(f"input length {n} must be a multiple of {WIDTH}")
        data = []
        for a in arrays:
            a = np.asarray(a, dtype=np.float32)
            full = np.zeros((n, 4), dtype=np.float32)
            full[:, :a.shape[1]] = a
            data.append(base64.b64encode(full.tobytes()).decode())
        self.shape = (WIDTH, n // WIDTH)
        self.page.evaluate("([l, w, h]) => setInputs(l, w, h)", [data, *self.shape])

    def run(self, jobs):
        """``jobs``: ``[(source, uniforms), ...]`` (a fragment shader's declarations
        and functions, and the body of ``main`` as a pair ``(code, body)``).
        Returns one ``(N, 4)`` float32 array per job, or the compile error text."""
        js = [{"src": HEADER + code + (MAIN % body), "uniforms": uniforms}
              for (code, body), uniforms in jobs]
        res = self.page.evaluate("([j, w, h]) => runMany(j, w, h)", [js, *self.shape])
        out = []
        for r in res:
            if r["ok"]:
                out.append(np.frombuffer(base64.b64decode(r["data"]), dtype=np.float32).reshape(-1, 4))
            else:
                out.append(r["error"])
        return out
