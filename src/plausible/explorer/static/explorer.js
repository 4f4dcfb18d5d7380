// plausible explorer: the page.  Every number shown comes from the server
// (plausible's library) or from the model's exported GLSL; nothing here
// evaluates a BRDF formula of its own.
"use strict";

const COLORS = { A: "#1f77b4", B: "#ff7f0e" };
const state = {
  models: [], byName: {},
  sides: { A: null, B: null },          // {name, params, shader, program, uniforms}
  thetaI: 30, light: [-0.45, 0.55, 0.70], exposure: 0, env: 0.3, logPlot: false,
  data: { A: {}, B: {} },               // last view data per side (read by the tests)
  lobeTurn: 0.6, pending: 0,
  perLobe: true,                        // each lobe (polar plot, 3-D lobe) to its own maximum
  plotScale: {}, lobeScale: {},         // the maximum each side's curve is drawn against (read by the tests)
  albedoAxis: null,                     // {top, ticks} of the albedo plot's y axis
};
window.explorer = state;

// -- server --------------------------------------------------------------------
async function api(path, body) {
  state.pending++;
  try {
    const r = await fetch(path, body === undefined ? {} : {
      method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
    const ct = r.headers.get("content-type") || "";
    const out = ct.includes("json") ? await r.json() : await r.text();
    if (!r.ok) {
      const e = new Error(out && out.error ? out.error : `${path}: HTTP ${r.status}`);
      e.status = r.status;        // 422: the model refused the parameters
      throw e;
    }
    return out;
  } finally { state.pending--; }
}

function setStatus(text, error = false) {
  const s = document.getElementById("status");
  s.textContent = text;
  s.className = error ? "error" : "";
}

function clone(x) { return JSON.parse(JSON.stringify(x)); }

function debounce(fn, ms) {
  let t = null;
  return (...a) => { clearTimeout(t); t = setTimeout(() => fn(...a), ms); };
}

// -- parameter controls ------------------------------------------------------------
function toSlider(p, v) {
  if (p.scale === "log") return Math.log1p(v - p.lo) / Math.log1p(p.hi - p.lo);
  return (v - p.lo) / (p.hi - p.lo);
}
function fromSlider(p, t) {
  let v = p.scale === "log" ? p.lo + Math.expm1(t * Math.log1p(p.hi - p.lo)) : p.lo + t * (p.hi - p.lo);
  v = Math.min(Math.max(v, p.lo), p.hi);
  return p.integer ? Math.round(v) : v;
}
function clamp(p, v) { return Math.min(Math.max(v, p.lo), p.hi); }
function hex(rgb) {
  const c = (x) => Math.round(Math.min(Math.max(x, 0), 1) * 255).toString(16).padStart(2, "0");
  return "#" + rgb.map(c).join("");
}
function unhex(h) { return [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16) / 255); }

function buildControls(side) {
  const box = document.getElementById(`params-${side}`);
  box.innerHTML = "";
  const s = state.sides[side];
  if (!s) return;
  const m = state.byName[s.name];
  document.getElementById(`desc-${side}`).textContent = m.description;
  for (const p of m.params) {
    const div = document.createElement("div");
    div.className = "param";
    div.dataset.param = p.name;
    const label = document.createElement("label");
    // a choice's options are in its menu: the label names it (a material's 100 names are not a label)
    label.textContent = p.kind === "choice" ? `${p.name} (${p.choices.length} choices)` : `${p.name} ${p.range}`;
    label.title = p.doc;
    div.appendChild(label);
    const v = s.params[p.name];
    if (p.kind === "scalar") {
      const r = document.createElement("input");
      r.type = "range"; r.min = 0; r.max = 1; r.step = 0.001; r.value = toSlider(p, v);
      r.setAttribute("aria-label", `${side} ${p.name}`);
      const n = document.createElement("input");
      n.type = "number"; n.min = p.lo; n.max = p.hi; n.step = "any"; n.value = +v.toPrecision(6);
      r.addEventListener("input", () => { const x = fromSlider(p, +r.value); n.value = +x.toPrecision(6); setParam(side, p.name, x); });
      n.addEventListener("change", () => {
        let x = +n.value;
        if (!Number.isFinite(x)) x = s.params[p.name];
        x = clamp(p, x); n.value = x; r.value = toSlider(p, x); setParam(side, p.name, x);
      });
      div.append(r, n);
    } else if (p.kind === "color") {
      const rgb = Array.isArray(v) ? v : [v, v, v];
      const c = document.createElement("input");
      c.type = "color"; c.value = hex(rgb.map((x) => clamp(p, x)));
      c.setAttribute("aria-label", `${side} ${p.name}`);
      const g = document.createElement("input");
      g.type = "range"; g.min = 0; g.max = 1; g.step = 0.001;
      g.value = Math.max(...rgb) > 0 ? Math.max(...rgb) / Math.min(p.hi, 1) : 0;
      g.title = "brightness";
      const apply = () => {
        const base = unhex(c.value); const mx = Math.max(...base, 1e-9);
        const k = (+g.value) * Math.min(p.hi, 1);
        const col = base.map((x) => clamp(p, (x / mx) * k));
        setParam(side, p.name, col);
      };
      c.addEventListener("input", apply); g.addEventListener("input", apply);
      div.append(c, g);
    } else if (p.kind === "choice") {
      const sel = document.createElement("select");
      for (const ch of p.choices) { const o = document.createElement("option"); o.value = o.textContent = ch; sel.appendChild(o); }
      sel.value = v; sel.setAttribute("aria-label", `${side} ${p.name}`);
      sel.addEventListener("change", () => setParam(side, p.name, sel.value, true));
      div.appendChild(sel);
    } else {
      const t = document.createElement("input");
      t.type = "text"; t.value = v; t.setAttribute("aria-label", `${side} ${p.name}`);
      t.addEventListener("change", () => setParam(side, p.name, t.value, true));
      div.appendChild(t);
    }
    box.appendChild(div);
  }
}

function body(side, extra = {}) {
  const s = state.sides[side];
  return Object.assign({ model: s.name, params: s.params, theta_i: state.thetaI }, extra);
}

async function selectModel(side, name) {
  if (!name) {
    state.sides[side] = null; state.data[side] = {};
    document.getElementById(`params-${side}`).innerHTML = "";
    document.getElementById(`desc-${side}`).textContent = "";
    document.getElementById(`sphere-${side}`).hidden = true;
    document.getElementById(`slice-${side}`).hidden = true;
    document.getElementById(`verdict-${side}`).innerHTML = "";
    redrawPlots(); drawSliceBar(); return;
  }
  const m = state.byName[name];
  const params = {};
  for (const p of m.params) params[p.name] = p.default;
  state.sides[side] = { name, params, valid: clone(params) };
  state.data[side] = {};
  markComputing(side);
  document.getElementById(`sphere-${side}`).hidden = false;
  document.getElementById(`slice-${side}`).hidden = false;
  buildControls(side);
  await refreshShader(side);
  refreshFast(side); refreshSlowSoon[side]();
}

function setParam(side, name, value, structural = false) {
  const s = state.sides[side];
  s.params[name] = value;
  markComputing(side);
  const u = s.uniforms && s.uniforms.find((x) => x.param === name);
  if (u && !structural) { drawSphere(side); } else { refreshShaderSoon[side](); }
  refreshFastSoon[side](); refreshSlowSoon[side]();
}

// -- WebGL2 sphere -------------------------------------------------------------------
const VERT = `#version 300 es
in vec2 pos; out vec2 uv;
void main() { uv = pos * 0.5 + 0.5; gl_Position = vec4(pos, 0.0, 1.0); }`;

function envDirs(k) {   // stratified directions about the view's up axis (+y), for the sky term
  const out = [];
  for (let i = 0; i < k; i++) {
    const z = Math.sqrt(1 - (i % 4 + 0.5) / 4), r = Math.sqrt(1 - z * z), ph = 2 * Math.PI * (Math.floor(i / 4) + 0.5) / (k / 4);
    out.push([r * Math.cos(ph), z, r * Math.sin(ph)]);
  }
  return out;
}
const ENV = envDirs(32);

function fragment(shader) {
  const fn = shader.function;
  return `#version 300 es
precision highp float;
precision highp int;
in vec2 uv; out vec4 outColor;
uniform vec3 u_light; uniform float u_exposure; uniform float u_env; uniform vec3 u_envdir[32];
${shader.source}
void main() {
  vec2 p = uv * 2.0 - 1.0; float r2 = dot(p, p);
  if (r2 >= 1.0) { outColor = vec4(0.27, 0.27, 0.27, 1.0); return; }
  vec3 n = vec3(p, sqrt(1.0 - r2));
  float sg = n.z >= 0.0 ? 1.0 : -1.0; float a = -1.0 / (sg + n.z); float b = n.x * n.y * a;
  vec3 s = vec3(1.0 + sg * n.x * n.x * a, sg * b, -sg * n.x);
  vec3 t = vec3(b, sg + n.y * n.y * a, -n.y);
  vec3 V = vec3(0.0, 0.0, 1.0);
  vec3 wo = vec3(dot(V, s), dot(V, t), dot(V, n));
  vec3 L = normalize(u_light);
  vec3 wi = vec3(dot(L, s), dot(L, t), dot(L, n));
  vec3 rad = vec3(0.0);
  if (wi.z > 0.0) rad += ${fn}(wi, wo) * wi.z * 3.14159265;
  for (int k = 0; k < 32; k++) {
    vec3 d = u_envdir[k]; vec3 l = vec3(dot(d, s), dot(d, t), dot(d, n));
    if (l.z > 0.0) rad += ${fn}(l, wo) * l.z * u_env * (6.2831853 / 32.0);
  }
  vec3 c = vec3(1.0) - exp(-max(rad, vec3(0.0)) * exp2(u_exposure));
  outColor = vec4(pow(c, vec3(1.0 / 2.2)), 1.0);
}`;
}

function glFor(side) {
  const canvas = document.getElementById(`sphere-${side}`);
  if (!canvas._gl) {
    const gl = canvas.getContext("webgl2", { preserveDrawingBuffer: true, antialias: false });
    if (!gl) throw new Error("WebGL2 is not available in this browser");
    const buf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    canvas._gl = gl; canvas._buf = buf;
    canvas.addEventListener("pointerdown", (e) => { canvas._drag = true; moveLight(canvas, e); });
    canvas.addEventListener("pointermove", (e) => { if (canvas._drag) moveLight(canvas, e); });
    window.addEventListener("pointerup", () => { canvas._drag = false; });
  }
  return canvas._gl;
}

function moveLight(canvas, e) {
  const r = canvas.getBoundingClientRect();
  const x = ((e.clientX - r.left) / r.width) * 2 - 1, y = 1 - ((e.clientY - r.top) / r.height) * 2;
  const r2 = x * x + y * y;
  state.light = r2 < 1 ? [x, y, Math.sqrt(1 - r2)] : [x / Math.sqrt(r2), y / Math.sqrt(r2), 0.02];
  drawSphere("A"); drawSphere("B");
}

function compile(gl, type, src) {
  const sh = gl.createShader(type);
  gl.shaderSource(sh, src); gl.compileShader(sh);
  if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error("GLSL: " + gl.getShaderInfoLog(sh));
  return sh;
}

// A verdict takes seconds: the old one goes at once and a sign says one is coming.
function markComputing(side) {
  state.data[side].verdict = null; state.data[side].verdictPending = true;
  document.getElementById(`verdict-${side}`).innerHTML =
    `<p class="computing"><b style="color:${COLORS[side]}">${side}</b>: computing the verdict (a few seconds)…</p>`;
}

// A parameter set the model refuses (422): the controls, the sphere and the plots go back
// to the last set it accepted, and the status line says why (the model's own message).
function refuse(side, e, my) {
  const s = state.sides[side];
  if (!s || stamp(side) !== my) return;            // a stale answer: the side has moved on
  if (e.status !== 422 || !s.valid) { setStatus(e.message, true); return; }
  s.params = clone(s.valid);
  buildControls(side);
  refreshShader(side);
  refreshSlowSoon[side]();
  setStatus(`${side}: refused: ${e.message}. Back to the last valid values.`, true);
}

async function refreshShader(side) {
  const s = state.sides[side];
  if (!s) return;
  const my = stamp(side);
  try {
    const sh = await api("/api/shader", body(side, { prefix: `m${side}` }));
    const gl = glFor(side);
    const prog = gl.createProgram();
    gl.attachShader(prog, compile(gl, gl.VERTEX_SHADER, VERT));
    gl.attachShader(prog, compile(gl, gl.FRAGMENT_SHADER, fragment(sh)));
    gl.bindAttribLocation(prog, 0, "pos");
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error("GLSL link: " + gl.getProgramInfoLog(prog));
    if (s.program) gl.deleteProgram(s.program);
    s.program = prog; s.uniforms = sh.uniforms; s.source = sh.source;
    drawSphere(side);
  } catch (e) { refuse(side, e, my); }
}
const refreshShaderSoon = { A: debounce(() => refreshShader("A"), 150), B: debounce(() => refreshShader("B"), 150) };

function drawSphere(side) {
  const s = state.sides[side];
  if (!s || !s.program) return;
  const gl = glFor(side);
  gl.viewport(0, 0, gl.canvas.width, gl.canvas.height);
  gl.useProgram(s.program);
  const loc = (n) => gl.getUniformLocation(s.program, n);
  gl.uniform3fv(loc("u_light"), state.light);
  gl.uniform1f(loc("u_exposure"), state.exposure);
  gl.uniform1f(loc("u_env"), state.env);
  gl.uniform3fv(loc("u_envdir"), new Float32Array(ENV.flat()));
  for (const u of s.uniforms) {
    const v = s.params[u.param];
    if (u.type === "vec3") {
      const c = Array.isArray(v) ? v : [v, v, v];
      gl.uniform3f(loc(u.name), c[0], c[1], c[2]);
    } else {
      gl.uniform1f(loc(u.name), Array.isArray(v) ? v.reduce((a, b) => a + b, 0) / v.length : +v);
    }
  }
  gl.bindBuffer(gl.ARRAY_BUFFER, gl.canvas._buf);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  s.drawn = (s.drawn || 0) + 1;
}

// -- views from the server -------------------------------------------------------------
// A response is drawn only if the side still shows what was asked (model, parameters, incidence).
function stamp(side) { const s = state.sides[side]; return s && JSON.stringify([s.name, s.params, state.thetaI]); }

async function refreshFast(side) {
  const s = state.sides[side];
  if (!s) return;
  const my = stamp(side), asked = clone(body(side));
  try {
    const val = await api("/api/validate", asked);     // first: a refused set draws nothing
    if (stamp(side) !== my) return;
    s.valid = clone(asked.params);
    const [pl, lobe, sl] = await Promise.all([api("/api/plane", asked), api("/api/lobe3d", asked),
      api("/api/slice", asked)]);
    if (stamp(side) !== my) return;
    Object.assign(state.data[side], { plane: pl, lobe: lobe, slice: sl, asked: asked });
    document.getElementById("spec-A").textContent = side === "A" ? val.model : document.getElementById("spec-A").textContent;
    setStatus("");
    drawSlice(side); redrawPlots();
  } catch (e) { refuse(side, e, my); }
}
async function refreshSlow(side) {
  const s = state.sides[side];
  if (!s) return;
  const my = stamp(side).replace(/,[^,]*\]$/, "");      // the albedo and the verdict do not depend on theta_i
  const same = () => state.sides[side] && stamp(side).replace(/,[^,]*\]$/, "") === my;
  const full = stamp(side);
  try {
    const alb = await api("/api/albedo", body(side));
    if (!same()) return;
    state.data[side].albedo = alb; redrawPlots(); albedoTable();
    const v = await api("/api/check", body(side));
    if (!same()) return;
    state.data[side].verdict = v; state.data[side].verdictPending = false; drawVerdict(side);
  } catch (e) { if (same()) refuse(side, e, full); }
}
const refreshFastSoon = { A: debounce(() => refreshFast("A"), 40), B: debounce(() => refreshFast("B"), 40) };
const refreshSlowSoon = { A: debounce(() => refreshSlow("A"), 700), B: debounce(() => refreshSlow("B"), 700) };

function redrawPlots() {
  document.body.classList.toggle("compare", !!state.sides.B);
  drawPolar(); drawLobe(); drawAlbedo(); skyNote();
}

// Half-maximum width (degrees) of a side's lobe in the plane of incidence, from the server's plane data.
function lobeWidth(side) {
  const d = state.data[side].plane; if (!d) return null;
  const top = Math.max(...d.fcos); if (!(top > 0)) return null;
  const above = d.theta_o.filter((t, i) => d.fcos[i] >= 0.5 * top);
  return Math.max(...above) - Math.min(...above) + (d.theta_o[1] - d.theta_o[0]);
}

// The sky is 32 directional lights: a lobe narrower than their spacing mirrors each as a dot. Say so.
const NARROW_DEG = 20;
function skyNote() {
  const narrow = sides().map((k) => [k, lobeWidth(k)]).filter(([, w]) => w !== null && w < NARROW_DEG);
  state.narrow = Object.fromEntries(narrow);
  const note = document.getElementById("sky-note");
  note.textContent = narrow.length && state.env > 0 ?
    `${narrow.map(([k, w]) => `${k}: a narrow lobe (half-maximum width about ${w.toFixed(0)}°)`).join("; ")}: ` +
    `the separate bright dots are the sky's 32 directional lights, each mirrored by the lobe, not a defect; ` +
    `set the environment to 0 to see the point light alone.` : "";
}

function sides() { return ["A", "B"].filter((k) => state.sides[k]); }

function drawPolar() {
  const c = document.getElementById("polar"), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const cx = c.width / 2, cy = c.height - 15, R = Math.min(cx, cy) - 10;
  g.strokeStyle = "#ccc";
  for (const f of [0.25, 0.5, 0.75, 1]) { g.beginPath(); g.arc(cx, cy, R * f, Math.PI, 2 * Math.PI); g.stroke(); }
  g.beginPath(); g.moveTo(cx - R, cy); g.lineTo(cx + R, cy); g.stroke();
  const ti = state.thetaI * Math.PI / 180;     // light on the -x side
  g.strokeStyle = "#e0a000"; g.beginPath(); g.moveTo(cx, cy); g.lineTo(cx - R * Math.sin(ti), cy - R * Math.cos(ti)); g.stroke();
  const tops = {};
  for (const k of sides()) { const d = state.data[k].plane; if (d) tops[k] = Math.max(...d.fcos); }
  const top = Math.max(0, ...Object.values(tops));
  if (top <= 0) return;
  state.plotScale = {};
  for (const k in tops) state.plotScale[k] = state.perLobe && tops[k] > 0 ? tops[k] : top;
  const tr = (v, t) => state.logPlot ? Math.max(0, 1 + Math.log10(Math.max(v / t, 1e-4)) / 4) : v / t;
  for (const k of sides()) {
    const d = state.data[k].plane; if (!d) continue;
    const sc = state.plotScale[k];
    g.strokeStyle = COLORS[k]; g.lineWidth = 2; g.beginPath();
    d.theta_o.forEach((t, i) => {
      const a = t * Math.PI / 180, r = R * tr(d.fcos[i], sc);
      const x = cx + r * Math.sin(a), y = cy - r * Math.cos(a);
      i ? g.lineTo(x, y) : g.moveTo(x, y);
    });
    g.stroke(); g.lineWidth = 1;
  }
  g.fillStyle = "#555"; g.font = "11px sans-serif";
  const several = Object.keys(tops).length > 1;
  if (several && state.perLobe) {
    g.fillText(`max f·cos: ${Object.keys(tops).map((k) => `${k} ${tops[k].toPrecision(4)}`).join(", ")} ` +
      `(each lobe to its own scale)${state.logPlot ? " (4 decades)" : ""}`, 5, 12);
  } else {
    g.fillText(`max f·cos = ${top.toPrecision(4)}${state.logPlot ? " (4 decades)" : ""}`, 5, 12);
  }
}

function drawLobe() {
  const c = document.getElementById("lobe3d"), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const tops = {};
  for (const k of sides()) { const d = state.data[k].lobe; if (d) tops[k] = Math.max(...d.fcos.map((row) => Math.max(...row))); }
  const top = Math.max(0, ...Object.values(tops));
  if (top <= 0) return;
  state.lobeScale = {};
  for (const k in tops) state.lobeScale[k] = state.perLobe && tops[k] > 0 ? tops[k] : top;
  const az = state.lobeTurn, el = 0.45, S = Math.min(c.width, c.height) * 0.42, ox = c.width / 2, oy = c.height * 0.8;
  const proj = (x, y, z) => {
    const x1 = x * Math.cos(az) - y * Math.sin(az), y1 = x * Math.sin(az) + y * Math.cos(az);
    return [ox + S * x1, oy - S * (z * Math.cos(el) - y1 * Math.sin(el))];
  };
  g.strokeStyle = "#bbb"; g.beginPath();
  for (let i = 0; i <= 64; i++) { const a = 2 * Math.PI * i / 64; const [x, y] = proj(Math.cos(a), Math.sin(a), 0); i ? g.lineTo(x, y) : g.moveTo(x, y); }
  g.stroke();
  for (const k of sides()) {
    const d = state.data[k].lobe; if (!d) continue;
    const P = d.theta.map((t, i) => d.phi.map((p, j) => {
      const r = d.fcos[i][j] / state.lobeScale[k], T = t * Math.PI / 180, F = p * Math.PI / 180;
      return proj(r * Math.sin(T) * Math.cos(F), r * Math.sin(T) * Math.sin(F), r * Math.cos(T));
    }));
    g.strokeStyle = COLORS[k]; g.globalAlpha = 0.55; g.beginPath();
    for (const row of P) row.forEach(([x, y], j) => (j ? g.lineTo(x, y) : g.moveTo(x, y)));
    for (let j = 0; j < d.phi.length; j += 2) P.forEach((row, i) => (i ? g.lineTo(row[j][0], row[j][1]) : g.moveTo(row[j][0], row[j][1])));
    g.stroke(); g.globalAlpha = 1;
  }
}
(() => {
  const c = document.getElementById("lobe3d");
  let last = null;
  c.addEventListener("pointerdown", (e) => { last = e.clientX; });
  c.addEventListener("pointermove", (e) => { if (last !== null) { state.lobeTurn += (e.clientX - last) / 80; last = e.clientX; drawLobe(); } });
  window.addEventListener("pointerup", () => { last = null; });
})();

function channelMean(v) { return Array.isArray(v) ? v.reduce((a, b) => a + b, 0) / v.length : v; }

function drawAlbedo() {
  const c = document.getElementById("albedo"), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const L = 40, B = c.height - 25, W = c.width - L - 10, H = B - 10;
  // the y axis covers every curve, its band and the energy markers (the largest channel)
  let top = 1.1;
  const colour = [];
  for (const k of sides()) {
    const a = state.data[k].albedo; if (!a) continue;
    a.value.forEach((v, i) => { top = Math.max(top, (channelMean(v) + channelMean(a.error[i])) * 1.05); });
    top = Math.max(top, ...a.max.map((x) => x * 1.05));
    if (Array.isArray(a.value[0])) colour.push(`${k}: mean of its ${a.value[0].length} channels`);
  }
  const ticks = niceTicks(top);
  state.albedoAxis = { top, ticks };
  document.getElementById("albedo-note").textContent = colour.length ?
    `; colour models show the channel mean (${colour.join("; ")}); red marks: the largest channel` : "";
  const X = (t) => L + W * t / 90, Y = (v) => B - H * Math.min(v, top) / top;
  g.strokeStyle = "#999"; g.strokeRect(L, 10, W, H);
  g.fillStyle = "#555"; g.font = "11px sans-serif";
  for (const t of [0, 30, 60, 90]) g.fillText(`${t}°`, X(t) - 8, B + 14);
  for (const v of ticks) g.fillText(+v.toPrecision(3) + "", 4, Y(v) + 4);
  g.setLineDash([4, 3]); g.strokeStyle = "#888"; g.beginPath(); g.moveTo(L, Y(1)); g.lineTo(L + W, Y(1)); g.stroke(); g.setLineDash([]);
  for (const k of sides()) {
    const a = state.data[k].albedo; if (!a) continue;
    const v = a.value.map(channelMean), e = a.error.map(channelMean);
    g.fillStyle = COLORS[k] + "44"; g.beginPath();
    a.theta.forEach((t, i) => (i ? g.lineTo(X(t), Y(v[i] + e[i])) : g.moveTo(X(t), Y(v[i] + e[i]))));
    for (let i = a.theta.length - 1; i >= 0; i--) g.lineTo(X(a.theta[i]), Y(v[i] - e[i]));
    g.fill();
    g.strokeStyle = COLORS[k]; g.lineWidth = 2; g.beginPath();
    a.theta.forEach((t, i) => (i ? g.lineTo(X(t), Y(v[i])) : g.moveTo(X(t), Y(v[i]))));
    g.stroke(); g.lineWidth = 1;
    g.fillStyle = "#d00";
    for (const t of a.energy_gained_at) { const i = a.theta.indexOf(t); g.beginPath(); g.arc(X(t), Y(a.max[i]), 4, 0, 2 * Math.PI); g.fill(); }
  }
}

// Round tick values from 0 up to (at most) top: 4 to 8 of them, steps of 1, 2 or 5 times a power of 10.
function niceTicks(top) {
  const raw = top / 5, p = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((m) => m * p).find((s) => top / s <= 8);
  const out = [];
  for (let v = 0; v <= top + 1e-12; v += step) out.push(+v.toPrecision(12));
  return out;
}

function albedoTable() {
  const t = document.getElementById("albedo-table");
  const rows = ["<tr><th></th><th>θ</th><th>albedo</th><th>± bound</th></tr>"];
  for (const k of sides()) {
    const a = state.data[k].albedo; if (!a) continue;
    for (const i of [0, Math.floor(a.theta.length / 2), a.theta.length - 1]) {
      rows.push(`<tr data-side="${k}" data-theta="${a.theta[i]}"><td>${k}</td><td>${a.theta[i].toFixed(1)}°</td>` +
        `<td class="albedo-value">${channelMean(a.value[i]).toPrecision(6)}</td><td>${channelMean(a.error[i]).toExponential(1)}</td></tr>`);
    }
    if (a.energy_gained_at.length) rows.push(`<tr><td>${k}</td><td colspan="3" class="fail">energy gained at ${a.energy_gained_at.map((x) => x.toFixed(1) + "°").join(", ")}</td></tr>`);
  }
  t.innerHTML = rows.join("");
}

const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
function cmap(x) {
  x = Math.min(Math.max(x, 0), 1) * (VIRIDIS.length - 1);
  const i = Math.min(Math.floor(x), VIRIDIS.length - 2), f = x - i;
  return VIRIDIS[i].map((a, j) => a + f * (VIRIDIS[i + 1][j] - a));
}
function drawSlice(side) {
  const d = state.data[side].slice; if (!d) return;
  const c = document.getElementById(`slice-${side}`), g = c.getContext("2d");
  const n = d.f.length; c.width = c.height = n;
  const img = g.createImageData(n, n);
  let top = 0; for (const row of d.f) top = Math.max(top, ...row);
  state.data[side].sliceMax = top;
  for (let i = 0; i < n; i++) for (let j = 0; j < n; j++) {
    const v = d.f[i][j], x = v > 0 && top > 0 ? 1 + Math.log10(v / top) / 4 : 0;
    const [r, gg, b] = v > 0 ? cmap(x) : [0, 0, 0];
    const o = 4 * (i * n + j); img.data[o] = r; img.data[o + 1] = gg; img.data[o + 2] = b; img.data[o + 3] = 255;
  }
  g.putImageData(img, 0, 0);
  drawSliceBar();
}

// The colour bar of the slices: viridis over 4 decades below each slice's own maximum.
function drawSliceBar() {
  const c = document.getElementById("slice-bar"), g = c.getContext("2d");
  for (let y = 0; y < c.height; y++) {
    const [r, gg, b] = cmap(1 - y / (c.height - 1));
    g.fillStyle = `rgb(${r},${gg},${b})`; g.fillRect(0, y, c.width, 1);
  }
  const tops = sides().filter((k) => state.data[k].sliceMax !== undefined)
    .map((k) => `${k} ${state.data[k].sliceMax.toPrecision(4)}`);
  document.getElementById("slice-scale").innerHTML =
    `<span>max f (${tops.join(", ")})</span><span>10⁻² max</span><span>10⁻⁴ max; black: 0</span>`;
}

function drawVerdict(side) {
  const v = state.data[side].verdict, box = document.getElementById(`verdict-${side}`);
  if (!v) { box.innerHTML = ""; return; }
  const word = (r) => r.passed === null ? ["na", "not applicable"] : r.passed ? ["pass", "passes"] : ["fail", "FAILS"];
  const rows = v.results.map((r) => `<tr><td>${r.name}</td><td class="${word(r)[0]}">${word(r)[1]}</td>` +
    `<td>${typeof r.figure === "number" ? r.figure.toPrecision(4) : "—"}</td><td>${r.bound}</td></tr>`);
  box.innerHTML = `<p><b style="color:${COLORS[side]}">${side}: ${v.model}</b> — ` +
    `<span class="${v.as_claimed ? "pass" : "fail"}">${v.as_claimed ? "agrees with its claims" : "does not hold its claims"}</span> ` +
    `(claims: ${v.claims.reciprocal ? "" : "not "}reciprocal, ${v.claims.energy_conserving ? "" : "not "}energy conserving)</p>` +
    `<table><tr><th>check</th><th>verdict</th><th>figure</th><th>bound</th></tr>${rows.join("")}</table>`;
}

// -- export ----------------------------------------------------------------------------------
async function download(fmt) {
  const s = state.sides.A; if (!s) return;
  try {
    const r = await fetch("/api/export", { method: "POST", headers: { "Content-Type": "application/json" },
      body: JSON.stringify(body("A", { format: fmt })) });
    if (!r.ok) throw new Error((await r.json()).error);
    const name = (r.headers.get("content-disposition") || "").match(/filename="([^"]+)"/)[1];
    const url = URL.createObjectURL(await r.blob());
    const a = document.createElement("a"); a.href = url; a.download = name; document.body.appendChild(a); a.click();
    setTimeout(() => { URL.revokeObjectURL(url); a.remove(); }, 1000);
  } catch (e) { setStatus(e.message, true); }
}

// -- start ---------------------------------------------------------------------------------------
async function start() {
  state.models = await api("/api/models");
  for (const m of state.models) state.byName[m.name] = m;
  for (const side of ["A", "B"]) {
    const sel = document.getElementById(`model-${side}`);
    for (const m of state.models) { const o = document.createElement("option"); o.value = o.textContent = m.name; sel.appendChild(o); }
    sel.addEventListener("change", () => selectModel(side, sel.value));
  }
  const th = document.getElementById("theta-i");
  th.addEventListener("input", () => {
    state.thetaI = +th.value; document.getElementById("theta-i-out").textContent = `${(+th.value).toFixed(1)}°`;
    refreshFastSoon.A(); if (state.sides.B) refreshFastSoon.B(); drawPolar();
  });
  document.getElementById("exposure").addEventListener("input", (e) => { state.exposure = +e.target.value; drawSphere("A"); drawSphere("B"); });
  document.getElementById("env").addEventListener("input", (e) => { state.env = +e.target.value; drawSphere("A"); drawSphere("B"); skyNote(); });
  document.getElementById("log-plot").addEventListener("change", (e) => { state.logPlot = e.target.checked; drawPolar(); });
  document.getElementById("per-lobe").addEventListener("change", (e) => { state.perLobe = e.target.checked; drawPolar(); drawLobe(); });
  for (const b of document.querySelectorAll("#exports button")) b.addEventListener("click", () => download(b.dataset.format));
  const first = state.byName["ashikhmin-shirley"] ? "ashikhmin-shirley" : state.models[0].name;
  document.getElementById("model-A").value = first;
  await selectModel("A", first);
  state.ready = true;
}
start().catch((e) => setStatus(e.message, true));
