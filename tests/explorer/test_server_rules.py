"""The explorer server's rules (issue 27, docs/explorer.md): same-origin only, a
time and size budget per request with the server answering meanwhile, and 422
with the parameter named for every malformed request."""

import socket
import threading
import time

import pytest

fastapi = pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from plausible.explorer import views  # noqa: E402
from plausible.explorer.app import Budget, create_app, server_config  # noqa: E402

LOCAL = "http://127.0.0.1:8765"


@pytest.fixture(scope="module")
def client():
    return TestClient(create_app(port=8765), base_url=LOCAL)


def post(client, route, body, **kw):
    return client.post(f"/api/{route}", json=body, **kw)


def test_foreign_host_and_origin_are_refused(client):
    ok = {"model": "lambertian"}
    assert post(client, "validate", ok).status_code == 200
    assert post(client, "validate", ok, headers={"Origin": LOCAL}).status_code == 200
    assert post(client, "validate", ok, headers={"Origin": "http://localhost:8765"}).status_code == 200
    for origin in ("http://evil.example", "http://127.0.0.1:9999", "null", "https://127.0.0.1:8765"):
        r = post(client, "validate", ok, headers={"Origin": origin})
        assert r.status_code == 403 and "Origin" in r.json()["error"]
    for host in ("evil.example", "evil.example:8765", "127.0.0.1:9999", "127.0.0.1.evil.example:8765"):
        r = post(client, "validate", ok, headers={"Host": host})
        assert r.status_code == 403 and "Host" in r.json()["error"]
    assert client.get("/api/models", headers={"Host": "rebound.example:8765"}).status_code == 403


@pytest.mark.parametrize("body,names", [
    ({"model": "lambertian", "params": [1, 2]}, '"params"'),
    ({"model": "lambertian", "params": "rd=0.5"}, '"params"'),
    ({"model": "lambertian", "params": 3}, '"params"'),
    ({"model": 7}, '"model"'),
    ({"model": "lambertian", "theta_i": None}, "theta_i"),
    ({"model": "lambertian", "theta_i": [30]}, "theta_i"),
    ({"model": "lambertian", "theta_i": True}, "theta_i"),
    ({"model": "lafortune", "params": {"lobes": "2,2,2,1e6,0.5;"}}, "lobes"),
    ({"model": "ward", "params": {"alpha_x": True}}, "alpha_x"),
    ({"model": "lambertian", "params": {"rd": [0.1, 0.2]}}, "'rd'"),
    ({"model": "lambertian", "params": {"rd": "0.1,0.2,0.3,0.4"}}, "'rd'"),
    ({"model": "pumped-up", "params": {"base": "[" * 6 + "lambertian" + "]" * 6}}, "nests more than"),
    ({"model": "pumped-up", "params": {"base": "pumped-up:base=[" * 5 + "lambertian" + "]" * 5}}, "nests more than"),
])
def test_malformed_requests_get_422_naming_the_parameter(client, body, names):
    r = post(client, "plane", body)
    assert r.status_code == 422 and names in r.json()["error"]


def test_a_body_over_the_size_budget_or_not_json_is_refused(client):
    r = client.post("/api/validate", content=b'{"model": "lambertian", "params": {"rd": [' + b"0.5," * 30000
                    + b'0.5]}}', headers={"Content-Type": "application/json"})
    assert r.status_code == 413 and str(Budget().body_bytes) in r.json()["error"]
    r = client.post("/api/validate", content=b"{not json", headers={"Content-Type": "application/json"})
    assert r.status_code == 422 and "JSON" in r.json()["error"]


def test_a_request_over_the_time_budget_is_stopped_and_the_server_keeps_answering(monkeypatch):
    spinning = threading.Event()

    def spin(model):           # a view that never ends (pure Python, so it can be stopped)
        spinning.set()
        while True:
            pass

    monkeypatch.setattr(views, "half_diff_slice", spin)
    c = TestClient(create_app(budget=Budget(seconds=3.0)), base_url=LOCAL)
    answers = {}

    def slow():
        answers["slice"] = post(c, "slice", {"model": "lambertian"})

    th = threading.Thread(target=slow)
    th.start()
    assert spinning.wait(60)                                 # the slice computes (however slow the start)
    assert c.get("/api/models").status_code == 200
    assert "slice" not in answers                            # answered while the slice computes, before its 503
    th.join(30)
    r = answers["slice"]
    assert r.status_code == 503 and "time budget of 3 s" in r.json()["error"]
    # the worker was freed: the next computation is answered
    assert post(c, "plane", {"model": "lambertian", "theta_i": 10}).status_code == 200


def test_trickling_request_heads_and_bodies_are_cut_off():
    import uvicorn

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    budget = Budget(header_seconds=0.5, body_seconds=0.5)
    server = uvicorn.Server(server_config(create_app(port=port, budget=budget), "127.0.0.1", port, budget))
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    try:
        while not server.started:
            time.sleep(0.05)
        with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
            sock.sendall(b"GET /api/models HTTP/1.1\r\nHost: 127.0.0.1\r\n")   # the head never ends
            time.sleep(1.5)
            assert sock.recv(100) == b""        # closed by the server
        with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
            sock.sendall(f"POST /api/validate HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Type: "
                         f"application/json\r\nContent-Length: 100\r\n\r\n{{\"model\": ".encode())
            time.sleep(1.5)                     # the rest of the body never comes
            assert sock.recv(100).startswith(b"HTTP/1.1 408")
        with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
            sock.sendall(f"GET /api/models HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
            assert sock.recv(100).startswith(b"HTTP/1.1 200")
    finally:
        server.should_exit = True
        th.join(10)


# -- issue 45 item 6: closed to the network --------------------------------------------------

def test_an_empty_host_binds_loopback_and_only_a_named_address_is_exposed():
    from plausible.explorer import resolve_host, url_of

    assert resolve_host("") == ("127.0.0.1", False) and resolve_host(None) == ("127.0.0.1", False)
    assert resolve_host("localhost") == ("localhost", False) and resolve_host("::1") == ("::1", False)
    assert resolve_host("[::1]") == ("::1", False) and resolve_host("127.0.0.2") == ("127.0.0.2", False)
    for named in ("0.0.0.0", "::", "192.168.1.20", "explorer.example"):
        assert resolve_host(named) == (named, True)
    assert url_of("", 18998) == "http://localhost:18998/" and url_of("::", 9) == "http://localhost:9/"


def test_the_cli_binds_loopback_for_an_empty_host_and_warns_for_an_exposed_one(monkeypatch):
    from click.testing import CliRunner

    import plausible.explorer as ex
    from plausible.cli import main

    bound = []
    monkeypatch.setattr(ex, "bind", lambda host, port: bound.append(host) or object())
    monkeypatch.setattr(ex, "serve", lambda **kw: None)
    r = CliRunner().invoke(main, ["explore", "--host", "", "--port", "18998", "--no-browser"])
    assert r.exit_code == 0 and bound == ["127.0.0.1"]
    assert "http://localhost:18998/" in r.output and "WARNING" not in r.output
    r = CliRunner().invoke(main, ["explore", "--host", "0.0.0.0", "--port", "18998", "--no-browser"])
    assert r.exit_code == 0 and bound[-1] == "0.0.0.0"
    assert "WARNING" in r.output and "reachable from the network" in r.output


def test_a_forged_loopback_host_from_another_address_is_refused():
    ok = {"model": "lambertian"}
    remote = TestClient(create_app(host="0.0.0.0", port=8765), base_url=LOCAL, client=("192.0.2.7", 40000))
    for host in ("127.0.0.1:8765", "localhost:8765", "[::1]:8765"):
        r = post(remote, "validate", ok, headers={"Host": host})
        assert r.status_code == 403 and "192.0.2.7" in r.json()["error"]
    local = TestClient(create_app(host="0.0.0.0", port=8765), base_url=LOCAL, client=("127.0.0.1", 40000))
    assert post(local, "validate", ok).status_code == 200
    exposed = TestClient(create_app(host="192.0.2.1", port=8765), base_url="http://192.0.2.1:8765",
                         client=("192.0.2.7", 40000))
    assert post(exposed, "validate", ok).status_code == 200      # named address, named in Host: answered


@pytest.mark.parametrize("route", ["validate", "plane"])
@pytest.mark.parametrize("body", [b"[" * 30000, b'{"model": "lambertian", "params": {"rd": ' + b"[" * 5000 + b"]" * 5000
                                  + b"}}", b'{"model": "lambertian", "x": ' + b"[" * 100 + b"]" * 100 + b"}"])
def test_deeply_nested_json_is_refused_with_422(client, route, body):
    r = client.post(f"/api/{route}", content=body, headers={"Content-Type": "application/json"})
    assert r.status_code == 422 and "deep" in r.json()["error"]


def _stalled(monkeypatch, seconds):
    """Make the slice view a pure-Python wait of ``seconds`` (stoppable)."""
    def slow(model):
        t = time.monotonic()
        while time.monotonic() - t < seconds:
            time.sleep(0.01)
        return {}
    monkeypatch.setattr(views, "half_diff_slice", slow)


def test_validate_is_answered_while_heavy_requests_queue(monkeypatch):
    _stalled(monkeypatch, 2.0)
    c = TestClient(create_app(port=8765), base_url=LOCAL)
    heavy = [threading.Thread(target=post, args=(c, "slice", {"model": "lambertian"})) for _ in range(3)]
    for th in heavy:
        th.start()
    time.sleep(0.3)                                           # the slices hold the worker for about 6 s
    waits = []
    for _ in range(5):
        t = time.monotonic()
        assert post(c, "validate", {"model": "lambertian"}).status_code == 200
        waits.append(time.monotonic() - t)
    assert max(waits) < 1.0, waits
    for th in heavy:
        th.join(30)


def test_heavy_requests_beyond_the_queue_get_503_with_retry_after(monkeypatch):
    _stalled(monkeypatch, 1.5)
    c = TestClient(create_app(port=8765, budget=Budget(queue=2)), base_url=LOCAL)
    answers = []
    heavy = [threading.Thread(target=lambda: answers.append(post(c, "slice", {"model": "lambertian"})))
             for _ in range(2)]
    for th in heavy:
        th.start()
    time.sleep(0.3)
    r = post(c, "plane", {"model": "lambertian"})
    assert r.status_code == 503 and int(r.headers["Retry-After"]) >= 1 and "at most 2" in r.json()["error"]
    for th in heavy:
        th.join(30)
    assert [a.status_code for a in answers] == [200, 200]
    assert post(c, "plane", {"model": "lambertian"}).status_code == 200    # the queue drained
