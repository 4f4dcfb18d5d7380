#!/usr/bin/env bash
# One prepared run on a machine with an NVIDIA GPU (issue 42): the plugin suite on the CUDA variants,
# the float64 library on Dr.Jit's CUDA device, the figures report on cuda_ad_rgb, and the backend
# timings, summarised in $OUT/summary.md (OUT defaults to ./gpu-out).  Start it from the repository root:
#
#     bash scripts/gpu_check.sh            # about 6-8 minutes on an H200
#
# Mitsuba and Dr.Jit: taken from the Python environment, else from wheels in .whl/ (the cp312
# manylinux wheels of mitsuba and drjit; see docs/backends.md, "A GPU machine"), installed into
# /tmp/site.  Each step's exit status and time go into the summary; a failing step does not stop
# the others.
#
# DEVICE=llvm runs the same steps on the CPU (a rehearsal of the script itself; TESTS narrows the
# plugin suite, FIGURES_ARGS adds options to `plausible figures`, e.g. "--quick --only as-furnace").
set -u
export OUT=${OUT:-$PWD/gpu-out}
DEVICE=${DEVICE:-cuda}
TESTS=${TESTS:-tests/mitsuba}
FIGURES_ARGS=${FIGURES_ARGS:-}
mkdir -p "$OUT"
PY=${PYTHON:-python3}
export PYTHONPATH="$PWD/src${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1
if ! $PY -c "import mitsuba, drjit" 2>/dev/null && ls .whl/*.whl >/dev/null 2>&1; then
  mkdir -p /tmp/site
  for w in .whl/*.whl; do $PY -m zipfile -e "$w" /tmp/site/ >/dev/null; done
  export PYTHONPATH="$PYTHONPATH:/tmp/site"
fi
S="$OUT/summary.md"
{ echo "# gpu_check $(date -u +%FT%TZ)"; echo; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 | sed 's/^/GPU: /'
  $PY -m plausible.cli --version 2>&1; echo; } > "$S"

step() {  # step NAME TIMEOUT COMMAND...: run, log to $OUT/NAME.log, one line in the summary
  local name=$1 limit=$2; shift 2
  local t0=$SECONDS
  timeout "$limit" "$@" > "$OUT/$name.log" 2>&1
  local rc=$?
  echo "- $name: exit $rc in $((SECONDS - t0)) s; $(grep -E '(passed|failed|error)' "$OUT/$name.log" | tail -n 1)" >> "$S"
}

step "plugins-${DEVICE}_ad_rgb" 300 env PLAUSIBLE_TEST_VARIANT=${DEVICE}_ad_rgb $PY -m pytest -q -p no:cacheprovider --maxfail=30 $TESTS
step "backend-drjit" 120 $PY -m pytest -q -p no:cacheprovider tests/test_backend.py tests/test_drjit_front_end.py
step "figures-$DEVICE" 300 $PY -m plausible.cli figures --variant $DEVICE --out "$OUT/figures" --jobs 4 $FIGURES_ARGS
step timings 120 $PY - <<'PYEOF'
import json, os, time
import numpy as np
import plausible
from plausible.arrays import backend
out = {}
m = plausible.make("ashikhmin-shirley", nu=100.0, nv=1000.0)
rng = np.random.default_rng(1)
wi = rng.normal(size=(10**7, 3)); wi[:, 2] = abs(wi[:, 2]); wi /= np.linalg.norm(wi, axis=1)[:, None]
for dev in backend.devices():
    with backend.use(dev):
        m.eval(wi[:1000], wi[1000:2000])
        t = time.perf_counter(); m.eval(wi, wi[::-1]); out[f"eval 1e7 pairs, {dev}"] = time.perf_counter() - t
        t = time.perf_counter(); plausible.albedo_curve(m, thetas_deg=np.linspace(0, 89, 90))
        out[f"albedo curve 90 angles, {dev}"] = time.perf_counter() - t
        plausible.check(m, quick=True)
        t = time.perf_counter(); plausible.check(m, quick=True); out[f"check quick, {dev}"] = time.perf_counter() - t
print(json.dumps(out, indent=1))
json.dump(out, open(os.path.join(os.environ.get("OUT", "."), "timings.json"), "w"), indent=1)
print("1 passed, 0 failed")
PYEOF
grep -h "measured checks that do not hold\|figures that failed" "$OUT/figures-$DEVICE.log" >> "$S"
cat "$OUT/timings.json" >> "$S" 2>/dev/null
cat "$S"
