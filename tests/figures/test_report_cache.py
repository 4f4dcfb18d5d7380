"""The figures runner's cache and exit paths, on small fake figures (no rendering):
an interrupted remake leaves the previous figure whole, an interrupted run still
writes index.html, and the CLI reports unknown names, repeats and red checks."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import plausible.figures as F
from plausible.cli import main
from plausible.figures.report import _cached, input_key, run


def _stamp(ctx, interrupt_at=None):
    """Two data files holding the run's spp; Ctrl-C after the first when spp == interrupt_at."""
    ctx.steps(2)
    ctx.table("first", {"spp": np.array([ctx.base_spp])})
    ctx.tick()
    if ctx.base_spp == interrupt_at:
        raise KeyboardInterrupt
    ctx.table("second", {"spp": np.array([ctx.base_spp])})
    ctx.tick()
    ctx.measure("spp", ctx.base_spp, expected=16, tol=0.5)   # holds only at spp 16


@pytest.fixture
def fake(monkeypatch):
    F.names()   # load the real ones first, so that ours is not overwritten
    monkeypatch.setitem(F.FIGURES, "fake", F.Figure("fake", "Fake", "test", "caption", _stamp,
                                                    dict(interrupt_at=4096)))
    return "fake"


def _spp(path):
    return float(path.read_text().splitlines()[1])


def test_an_interrupted_remake_leaves_the_previous_figure_whole(tmp_path, fake):
    run(tmp_path, only=[fake], spp=16)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, only=[fake], spp=4096)
    d = tmp_path / fake
    assert _spp(d / "first.csv") == 16 and _spp(d / "second.csv") == 16      # not the interrupted run's 4096
    assert json.loads((d / "figure.json").read_text())["spp"] == 16
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []   # no partial folder left
    again = run(tmp_path, only=[fake], spp=16)
    assert again[fake]["cached"] is True


def test_an_interrupted_run_in_a_fresh_folder_writes_the_index_and_claims_nothing(tmp_path, fake):
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, only=[fake], spp=4096)
    assert (tmp_path / "index.html").exists()
    assert not (tmp_path / fake).exists()
    key = input_key(F.FIGURES[fake], resolution=None, spp=4096, quick=False)
    assert _cached(tmp_path / fake, key) is None
    assert run(tmp_path, only=[fake], spp=16)[fake]["cached"] is False


def test_figures_cli_unknown_name_creates_nothing(tmp_path):
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["figures", "--out", str(out), "--only", "nonexistent"])
    assert r.exit_code == 2 and "unknown figure 'nonexistent'" in r.output and "as-furnace" in r.output
    assert not out.exists()


def test_figures_cli_repeated_name_made_once_and_red_check_fails(tmp_path, fake):
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["figures", "--out", str(out), "--only", fake, "--only", fake, "--spp", "16"])
    assert r.exit_code == 0, r.output
    assert "1 figures (0 cached, 0 failed)" in r.output and "1/1 measured checks hold" in r.output
    r = CliRunner().invoke(main, ["figures", "--out", str(out), "--only", fake, "--spp", "8"])
    assert r.exit_code == 1
    assert "measured checks that do not hold (1): fake: spp" in r.output


def test_figures_cli_unwritable_folder(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = CliRunner().invoke(main, ["figures", "--out", str(blocker / "out"), "--only", "checks"])
    assert r.exit_code == 2 and "--out: cannot write into" in r.output and "Traceback" not in r.output
