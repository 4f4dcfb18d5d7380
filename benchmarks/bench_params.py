"""Issue 30: parameters as data.  Import time of ``plausible`` beyond NumPy, and
(see the functions below) the work that varies parameters: kernel compilations
counted by Dr.Jit's kernel history, fits, checks of new parameter sets, every
published fit checked in one command.  Each benchmark records the machine's
load average (``os.getloadavg``) next to its numbers: the machine is shared."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from conftest import record


def load() -> str:
    """The 1-, 5- and 15-minute load averages, as ``uptime`` prints them."""
    return "%.2f %.2f %.2f" % os.getloadavg()


def import_times(module: str) -> dict:
    """Cumulative import time (s) of every module ``python -X importtime -c 'import
    module'`` reports, in a fresh process."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    r = subprocess.run([sys.executable, "-X", "importtime", "-c", f"import {module}"], env=env,
                       capture_output=True, text=True, check=True)
    out = {}
    for line in r.stderr.splitlines():
        m = re.match(r"import time:\s+\d+ \|\s+(\d+) \|(\s*)(\S+)", line)
        if m:
            out[m.group(3)] = int(m.group(1)) * 1e-6
    return out


def test_import_time(benchmark):
    """``import plausible`` beyond NumPy (target 0.3 s): the cumulative import time
    of ``plausible`` minus that of ``numpy``, median of 5 fresh processes.  Also
    whether ``scipy.stats`` was imported.  Reference, same run: ``import scipy.stats``
    beyond NumPy, which ``plausible`` imported eagerly before issue 30."""
    runs = [import_times("plausible") for _ in range(5)]
    beyond = sorted(r["plausible"] - r.get("numpy", 0.0) for r in runs)
    ref = sorted(r["scipy.stats"] - r.get("numpy", 0.0) for r in (import_times("scipy.stats") for _ in range(5)))
    record(benchmark, "issue-30", "import plausible, beyond NumPy (s)", backend="-", op="import", n=1,
           beyond_numpy_s=beyond[2], numpy_s=sorted(r.get("numpy", 0.0) for r in runs)[2],
           scipy_stats="scipy.stats" in runs[0], reference_scipy_stats_s=ref[2], load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


# -- what varies parameters ----------------------------------------------------------------

import resource  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import plausible  # noqa: E402
from plausible.arrays import backend  # noqa: E402

needs_drjit = pytest.mark.skipif(not backend.drjit_available(), reason="Dr.Jit LLVM backend unavailable")


def cpu() -> float:
    """CPU seconds of this process (all its threads) and of its finished children."""
    me, ch = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + ch.ru_utime + ch.ru_stime


def timed(fn):
    """``(result, wall s, CPU s)`` of one call."""
    t, c = time.perf_counter(), cpu()
    out = fn()
    return out, time.perf_counter() - t, cpu() - c


#: (spec, parameter to vary, values): a new parameter set per value.
VARIED = [("ashikhmin-shirley:nu=10:nv=100", "nu", (11.0, 13.5, 27.0, 55.5, 80.25)),
          ("ward:alpha_x=0.1:alpha_y=0.1:rs=0.5:rd=0.2", "rs", (0.11, 0.23, 0.35, 0.47, 0.59)),
          ("cook-torrance:m=0.2:rs=0.6", "m", (0.11, 0.17, 0.23, 0.29, 0.35))]


@needs_drjit
@pytest.mark.parametrize("spec,name,values", VARIED, ids=[v[0].split(":")[0] for v in VARIED])
def test_new_parameter_sets_compile_nothing(benchmark, spec, name, values):
    """``eval`` of 10^5 pairs on Dr.Jit at five parameter sets never used before
    (the structure compiled once at the spec's own values): kernels compiled and
    milliseconds per set; reference, same run: the same with the structure forced
    to constants (one kernel per parameter set, as before issue 30).  The values
    are offset by the clock, so Dr.Jit's disk cache cannot know them."""
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(2, 100_000, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    base = plausible.registry.make_from_spec(spec)
    base.eval(wi, wo, backend="drjit")
    st = backend.structure_of(base)
    out = {}
    for mode in ("data", "constants"):
        off = 1.0 + (time.time_ns() % 10 ** 6) * 1e-9
        models = [type(base)(**dict(base.params, **{name: v * off})) for v in values]
        if mode == "constants":
            backend._CONSTANTS.add(st)
        try:
            with backend.kernel_log() as log:
                _, wall, _ = timed(lambda: [m.eval(wi, wo, backend="drjit") for m in models])
        finally:
            backend._CONSTANTS.discard(st)
        out[mode] = dict(compiled=log["compiled"] + log["loaded"], ms_per_set=1e3 * wall / len(models))
    record(benchmark, "issue-30", f"5 new parameter sets, eval 10^5 pairs ({spec.split(':')[0]})",
           backend="drjit", op="params", n=len(values), compiled_data=out["data"]["compiled"],
           compiled_constants=out["constants"]["compiled"], ms_per_set_data=out["data"]["ms_per_set"],
           ms_per_set_constants=out["constants"]["ms_per_set"], load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


#: Mitsuba prb optimisation: (plugin dict, parameters optimised).  Ward's alpha_x
#: is the reference: its step never recompiled.
STEPS = [("ward rs, rd", dict(type="ward", alpha_x=0.2, alpha_y=0.2, rs=0.5, rd=0.3), {"rs": 0.3, "rd": 0.5}),
         ("modified-phong kd, ks", dict(type="modified_phong", kd=0.4, ks=0.3, n=20), {"kd": 0.3, "ks": 0.2}),
         ("ward alpha_x (reference)", dict(type="ward", alpha_x=0.2, alpha_y=0.2, rs=0.5, rd=0.3),
          {"alpha_x": 0.3})]


@needs_drjit
@pytest.mark.parametrize("label,bsdf,start", STEPS, ids=[s[0].split(" (")[0].replace(" ", "") for s in STEPS])
def test_mitsuba_optimisation_step_compiles_nothing(benchmark, mi, label, bsdf, start):
    """``plausible.mitsuba.inverse.fit`` (Adam through ``prb``, 16x16, 2 spp): two
    warm-up steps, then kernels compiled (or loaded from disk) and milliseconds
    per step over 3 steps.  Before issue 30, a Python ``if`` on ``rs + rd``
    (``kd + ks``) made each step's parameter values kernel constants."""
    from plausible.mitsuba import inverse

    scene = inverse.sphere_scene(bsdf, res=16, spp=2)
    ref = mi.render(scene, seed=0, spp=2)
    inverse.fit(scene, ref, start, iterations=2)
    with backend.kernel_log() as log:
        _, wall, _ = timed(lambda: inverse.fit(scene, ref, start, iterations=3))
    record(benchmark, "issue-30", f"Mitsuba prb step: {label}", backend="mitsuba", op="step", n=3,
           compiled_per_step=(log["compiled"] + log["loaded"]) / 3, ms_per_step=1e3 * wall / 3, load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


def roughconductor_from_numpy(mi, op, wi, wo, u):
    """A call of Mitsuba's ``roughconductor`` (Beckmann, alpha 0.1, as in
    bench_throughput.py) on NumPy arrays, as a Mitsuba user makes it: the
    ``(n, 3)`` arrays converted to ``Vector3f`` (float32; NumPy's transposed
    copy is the faster of the two conversions measured, Dr.Jit's own from
    ``a.T`` the other), the interaction built, the BSDF called, its outputs
    evaluated together and read back as NumPy arrays."""
    import drjit as dr

    bsdf = mi.load_dict({"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1})
    ctx = mi.BSDFContext()

    def vec3(a):
        return mi.Vector3f(np.ascontiguousarray(a.T, dtype=np.float32))

    def call():
        si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
        si.wi = vec3(wi)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        if op == "sample":
            bs, w = bsdf.sample(ctx, si, mi.Float(np.ascontiguousarray(u[:, 0], dtype=np.float32)),
                                mi.Point2f(np.ascontiguousarray(u[:, 1:].T, dtype=np.float32)))
            dr.eval(bs.wo, bs.pdf, w)
            return bs.wo.numpy(), w.numpy(), bs.pdf.numpy()
        out = (bsdf.eval if op == "eval" else bsdf.pdf)(ctx, si, vec3(wo))
        return out.numpy()

    return call


@needs_drjit
@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize("op", ["eval", "pdf", "sample"])
def test_api_against_roughconductor_from_numpy(benchmark, mi, pairs, op, dtype):
    """Issue 30's "API ``eval`` of 10^6 pairs from NumPy arrays, against Mitsuba's
    ``roughconductor`` called on the same NumPy arrays (conversion included), in
    one run" (target: ratio <= 1), and the same for ``pdf`` and ``sample``.  The
    API: ``m.eval(wi, wo, backend="drjit")`` of Ashikhmin-Shirley (defaults),
    NumPy in, NumPy out, validation and normalisation included; the reference:
    :func:`roughconductor_from_numpy` on the same arrays.  Both compiled first,
    then ``ROUNDS`` alternating calls of each; medians of wall and CPU seconds
    (``getrusage``: every thread of the process), and the load average.
    ``dtype``: the arrays as given to both (float32 arrays enter the API's
    float64 kernel without a float64 copy)."""
    from conftest import ROUNDS

    wi, wo, u = (np.asarray(a, dtype=dtype) for a in pairs)
    m = plausible.make("ashikhmin-shirley")
    api = {"eval": lambda: m.eval(wi, wo, backend="drjit"), "pdf": lambda: m.pdf(wi, wo, backend="drjit"),
           "sample": lambda: m.sample(wi, u, backend="drjit")}[op]
    ref = roughconductor_from_numpy(mi, op, wi, wo, u)
    api(), ref()
    times = {"api": [], "ref": []}
    loads = [os.getloadavg()[0]]
    for _ in range(max(ROUNDS, 5)):
        for k, fn in (("api", api), ("ref", ref)):
            times[k].append(timed(fn)[1:])
        loads.append(os.getloadavg()[0])
    med = {k: [float(np.median([t[i] for t in v])) for i in (0, 1)] for k, v in times.items()}
    record(benchmark, "issue-30", f"API {op} of 10^6 pairs vs roughconductor from NumPy ({dtype})", backend="drjit",
           op=op, n=len(wi), api_wall_ms=1e3 * med["api"][0], api_cpu_ms=1e3 * med["api"][1],
           ref_wall_ms=1e3 * med["ref"][0], ref_cpu_ms=1e3 * med["ref"][1],
           ratio_wall=med["api"][0] / med["ref"][0], ratio_cpu=med["api"][1] / med["ref"][1],
           load_min=min(loads), load_max=max(loads), load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


#: ``check(quick=True)`` at a new parameter set: (name, warm-up parameters, the new ones,
#: their offset by the clock applied to); Ashikhmin-Shirley (anisotropic: 6 azimuths of
#: energy, 2 of sampling, 4 chi-square incidences) and Cook-Torrance (isotropic).
CHECKED = [("ashikhmin-shirley", dict(nu=10, nv=100), dict(nu=12, nv=90, rs=0.07), ("nu", "nv")),
           ("cook-torrance", dict(m=0.2, rs=0.6), dict(m=0.27, rs=0.5), ("m",))]


@needs_drjit
@pytest.mark.parametrize("backend_name", ["auto", "numpy"])
@pytest.mark.parametrize("name,warm,new,varied", CHECKED, ids=[c[0] for c in CHECKED])
def test_check_quick_of_a_new_parameter_set(benchmark, backend_name, name, warm, new, varied):
    """``check(quick=True)`` at a parameter set not seen before (after one check at
    other values: the kernels of the structure are compiled; the new values are offset
    by the clock, so neither Dr.Jit's caches nor an earlier run know them); target
    0.3 s.  Kernels launched and compiled (or loaded from disk) by Dr.Jit's kernel
    history.  Reference, same run: the NumPy backend."""
    with plausible.use_backend(backend_name):
        plausible.check(plausible.make(name, **warm), quick=True)
        off = (time.time_ns() % 10 ** 6) * 1e-9
        m = plausible.make(name, **{k: v * (1 + (off if k in varied else 0)) for k, v in new.items()})
        with backend.kernel_log() as log:
            rep, wall, cpus = timed(lambda: plausible.check(m, quick=True))
    record(benchmark, "issue-30", f"check --quick, new parameter set ({name})", backend=backend_name,
           op="check", n=1, wall_s=wall, cpu_s=cpus, passed=bool(rep.passed), launched=log["launched"],
           compiled=log["compiled"] + log["loaded"], load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


@needs_drjit
@pytest.mark.parametrize("metric", ["l2-cos", "perceptual"])
@pytest.mark.parametrize("backend_name", ["auto", "numpy"])
def test_fit_as_to_cook_torrance(benchmark, metric, backend_name):
    """``plausible fit ashikhmin-shirley --target cook-torrance:m=0.17:rs=0.6`` with
    ``metric`` (targets: perceptual 10 s, l2-cos 2 s); wall and CPU seconds
    (the CPU time is what a loaded machine does not inflate).  Reference,
    same run: the NumPy backend."""
    with plausible.use_backend(backend_name):
        res, wall, cpus = timed(lambda: plausible.fit("ashikhmin-shirley", "cook-torrance:m=0.17:rs=0.6",
                                                      metric=metric))
    record(benchmark, "issue-30", f"fit ashikhmin-shirley to cook-torrance m=0.17 rs=0.6, {metric}",
           backend=backend_name, op="fit", n=1, wall_s=wall, cpu_s=cpus, evaluations=int(res.evaluations),
           result=str({k: round(v, 4) for k, v in res.params.items() if isinstance(v, float)}), load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


#: A fit in a fresh process: its own CPU seconds (getrusage, all threads), wall
#: seconds and load around ``plausible.fit`` alone (imports and Dr.Jit's start excluded),
#: the evaluations, the parameters and every error figure, as JSON.
_FIT_SCRIPT = """
import json, os, resource, sys, time
import plausible, scipy.optimize
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
model, target, metric = sys.argv[1:4]
c, t = cpu(), time.perf_counter()
r = plausible.fit(model, target, metric=metric)
print(json.dumps(dict(cpu_s=cpu() - c, wall_s=time.perf_counter() - t, load=os.getloadavg()[0],
                      evaluations=r.evaluations, errors=r.errors,
                      params={k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in r.params.items()})))
"""

#: The fits of issue 30's fourth session: its target (A-S to Cook-Torrance, both metrics),
#: a published material and a colour target.
FIT_CASES = [("ashikhmin-shirley", "cook-torrance:m=0.17:rs=0.6", "perceptual"),
             ("ashikhmin-shirley", "cook-torrance:m=0.17:rs=0.6", "l2-cos"),
             ("ashikhmin-shirley", "material:nickel@ngan2005/ward", "perceptual"),
             ("ashikhmin-shirley", "cook-torrance:m=0.17:rs=0.6,0.5,0.4", "perceptual")]


def _fit_in(src, model, target, metric) -> dict:
    import json

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(src)] + [p for p in sys.path if p]))
    r = subprocess.run([sys.executable, "-c", _FIT_SCRIPT, model, target, metric], env=env,
                       capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def _max_rel(a: dict, b: dict) -> float:
    """The largest relative difference between two dicts of numbers (or lists)."""
    out = 0.0
    for k, v in a.items():
        if v is None or b.get(k) is None:
            continue
        x, y = np.asarray(v, float), np.asarray(b[k], float)
        out = max(out, float(np.max(np.abs(x - y) / np.maximum(np.abs(y), 1e-300))))
    return out


@needs_drjit
@pytest.mark.parametrize("model,target,metric", FIT_CASES, ids=[f"{t.split(':')[0]}-{m}" + ("-colour" if "," in t else "")
                                                                 for _, t, m in FIT_CASES])
def test_fit_against_reference_tree(benchmark, model, target, metric):
    """``plausible.fit(model, target, metric=...)`` in a fresh process of this tree,
    and, when ``PLAUSIBLE_BENCH_REF_SRC`` names the ``src`` folder of another
    tree (``main`` before a change: ``git archive COMMIT src | tar -x -C DIR``), of
    that tree right after it (the reference, same run): CPU and wall seconds of the
    fit alone, evaluations, the largest relative difference of the parameters and
    of the error figures between the two."""
    here = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")
    new = _fit_in(here, model, target, metric)
    info = dict(wall_s=new["wall_s"], cpu_s=new["cpu_s"], evaluations=new["evaluations"], load=new["load"],
                perceptual=new["errors"]["perceptual"], params=str(new["params"]))
    ref_src = os.environ.get("PLAUSIBLE_BENCH_REF_SRC")
    if ref_src:
        ref = _fit_in(ref_src, model, target, metric)
        info.update(ref_wall_s=ref["wall_s"], ref_cpu_s=ref["cpu_s"], ref_evaluations=ref["evaluations"],
                    ref_load=ref["load"], ref_perceptual=ref["errors"]["perceptual"],
                    params_max_rel=_max_rel(new["params"], ref["params"]),
                    errors_max_rel=_max_rel(new["errors"], ref["errors"]))
    record(benchmark, "issue-30", f"fit {model} to {target}, {metric} (fresh process)", backend="auto", op="fit",
           n=1, **info)
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


def _cli(*args):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    exe = os.path.join(os.path.dirname(sys.executable), "plausible")
    cmd = [exe] if os.path.exists(exe) else [sys.executable, "-m", "plausible.cli"]
    return subprocess.run(cmd + list(args), env=env, capture_output=True, text=True)


@pytest.mark.parametrize("args", [("--materials", "--json"), ("--materials", "--quick", "--json"),
                                  ("--all", "--quick", "--json")],
                         ids=["materials", "materials-quick", "all-quick"])
def test_check_command(benchmark, args):
    """``plausible check --materials`` (every published fit, 1202, at full accuracy;
    target 2 minutes), the same ``--quick``, and ``plausible check --all --quick``
    (every registered model on its defaults and extremes; target 20 s), each a fresh
    process: wall seconds and CPU seconds of the process and its workers.  For
    ``--materials`` also its verdicts (fits that gain energy, that are not
    reciprocal), which a speed-up must leave as they are."""
    r, wall, cpus = timed(lambda: _cli("check", *args))
    import json

    rows = json.loads(r.stdout) if r.stdout.strip().startswith("[") else None
    n = len(rows) if rows is not None else -1
    verdicts = {}
    if rows and "gains_energy" in rows[0]:
        verdicts = dict(gain_energy=sum(bool(x["gains_energy"]) for x in rows),
                        not_reciprocal=sum(not x["reciprocal"] for x in rows))
    record(benchmark, "issue-30", "plausible check " + " ".join(a for a in args if a != "--json"), backend="auto",
           op="check", n=n, wall_s=wall, cpu_s=cpus, status=r.returncode, load=load(), **verdicts)
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


@pytest.mark.parametrize("jobs", [2, 1])
def test_check_all_quick_jobs(benchmark, jobs):
    """``plausible check --all --quick --jobs N`` (target 20 s): two worker
    processes against one (the reference, same run), each a fresh process."""
    r, wall, cpus = timed(lambda: _cli("check", "--all", "--quick", "--json", "--jobs", str(jobs)))
    import json

    n = len(json.loads(r.stdout)) if r.stdout.strip().startswith("[") else -1
    record(benchmark, "issue-30", f"plausible check --all --quick --jobs {jobs}", backend="auto", op="check", n=n,
           wall_s=wall, cpu_s=cpus, status=r.returncode, load=load(),
           **(dict(stderr=r.stderr[-2000:]) if r.returncode else {}))
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


@needs_drjit
def test_explorer_slider(benchmark):
    """The explorer's answer to a slider move: ``views.verdict`` (``check(quick=True)``)
    and ``views.albedo`` (19 incidences) of a parameter set not seen before, after
    one of each at other values (targets 0.5 s and 0.2 s)."""
    from plausible.explorer import views

    views.verdict(views.build("ashikhmin-shirley", {"nu": 10, "nv": 100}))
    views.albedo(views.build("ashikhmin-shirley", {"nu": 10, "nv": 100}))
    off = (time.time_ns() % 10 ** 6) * 1e-7
    m = views.build("ashikhmin-shirley", {"nu": 14 + off, "nv": 80 - off})
    _, wall_v, cpu_v = timed(lambda: views.verdict(m))
    _, wall_a, cpu_a = timed(lambda: views.albedo(m))
    record(benchmark, "issue-30", "explorer slider: verdict / albedo (ashikhmin-shirley)", backend="auto",
           op="explorer", n=1, verdict_wall_s=wall_v, verdict_cpu_s=cpu_v, albedo_wall_s=wall_a,
           albedo_cpu_s=cpu_a, load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)


@pytest.mark.parametrize("jobs", [2, 1])
def test_demo(benchmark, tmp_path, jobs):
    """``make demo`` (``plausible figures --out DIR --jobs N`` in a fresh folder;
    target 90 s, issue 25: at most 165 s): two worker processes against one
    (the reference, same run).  Wall and CPU seconds, and the load."""
    r, wall, cpus = timed(lambda: _cli("figures", "--out", str(tmp_path / "out"), "--jobs", str(jobs)))
    last = (r.stdout.strip().splitlines() or [""])[-1]
    record(benchmark, "issue-30", f"make demo (plausible figures --jobs {jobs})", backend="auto", op="figures",
           n=1, wall_s=wall, cpu_s=cpus, status=r.returncode, summary=last[:200], load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
