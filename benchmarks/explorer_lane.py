"""Latency of /api/validate while heavy views queue (issue 45 item 6): a real uvicorn server on
loopback, 6 concurrent /api/check of anisotropic Ashikhmin-Shirley models (about 1 s each in the
one worker), then 13 polls of /api/validate 0.25 s apart (timeout 2 s each).  A script, not a
pytest benchmark:  PYTHONPATH=src python benchmarks/explorer_lane.py  (docs/benchmarks.md)."""
import json, socket, statistics, sys, threading, time, urllib.request
import uvicorn
from plausible.explorer.app import create_app

s = socket.socket(); s.bind(("127.0.0.1", 0)); port = s.getsockname()[1]; s.close()
server = uvicorn.Server(uvicorn.Config(create_app(port=port), host="127.0.0.1", port=port, log_level="warning"))
threading.Thread(target=server.run, daemon=True).start()
while not server.started:
    time.sleep(0.05)

def post(route, body, timeout):
    req = urllib.request.Request(f"http://127.0.0.1:{port}/api/{route}", json.dumps(body).encode(),
                                 {"Content-Type": "application/json"})
    t = time.monotonic()
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            r.read()
        return time.monotonic() - t, r.status
    except Exception as e:
        return time.monotonic() - t, type(e).__name__

res = []
heavy = [threading.Thread(target=lambda k=k: res.append(post("check", {"model": "ashikhmin-shirley",
         "params": {"nu": 10.0 + k, "nv": 1000.0}}, 120))) for k in range(6)]
for th in heavy:
    th.start()
time.sleep(0.5)
lat = []
for _ in range(13):
    lat.append(post("validate", {"model": "lambertian"}, 2.0))
    time.sleep(0.25)
ok = [t for t, st in lat if st == 200]
print(f"validate: {len(ok)}/13 answered within 2 s; median {statistics.median(t for t, _ in lat) * 1000:.0f} ms; "
      f"max {max(t for t, _ in lat) * 1000:.0f} ms")
for th in heavy:
    th.join()
print("heavy:", [(round(t, 1), st) for t, st in res])
server.should_exit = True
