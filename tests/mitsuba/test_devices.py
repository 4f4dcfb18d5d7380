"""Devices and variants (issue 42): what this machine renders and computes on, said and obeyed.

The CUDA paths are the LLVM paths with another array type; on a machine without a GPU these tests
check the choice, the refusals and the records, and ``scripts/gpu_check.sh`` runs the plugin suite
on the CUDA variants where a GPU exists."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from mi_helpers import VARIANT, dr, mi

from plausible.analysis.mitsuba_bsdf import device_exact
from plausible.arrays import backend
from plausible.mitsuba import variant


def _cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "plausible.cli", *args], capture_output=True, text=True,
                          env=env, timeout=300)


def test_the_preferred_variant_is_cuda_only_where_a_gpu_runs(monkeypatch):
    monkeypatch.delenv(variant.ENV, raising=False)
    gpu = backend.device_available("cuda")
    assert variant.preferred("rgb") == ("cuda_ad_rgb" if gpu else "llvm_ad_rgb")
    assert variant.preferred("spectral") == ("cuda_ad_spectral" if gpu else "llvm_ad_spectral")
    monkeypatch.setattr(variant, "available", lambda: ("cuda_ad_rgb", "cuda_ad_spectral", "llvm_ad_rgb"))
    assert variant.preferred("rgb") == "cuda_ad_rgb"
    variant.prefer("llvm")
    assert variant.preferred("spectral") == "llvm_ad_spectral"
    variant.prefer("cuda_ad_rgb")
    assert variant.preferred("rgb") == "cuda_ad_rgb"
    variant.prefer(None)
    assert variant.ENV not in os.environ


def test_the_variants_ask_the_backend_floor_which_devices_run(monkeypatch):
    """One probe of Dr.Jit's devices (``arrays.backend.device_available``) for the float64 backend and
    the Mitsuba variants: what it refuses renders no variant but a scalar one."""
    built = set(mi.variants())
    monkeypatch.setattr(backend, "device_available", lambda name: False)
    assert set(variant.available()) == {v for v in built if v.startswith("scalar_")}
    monkeypatch.setattr(backend, "device_available", lambda name: name == "llvm")
    assert set(variant.available()) == {v for v in built if v.startswith(("scalar_", "llvm_"))}
    assert not hasattr(variant, "device_runs")


def test_a_variant_that_cannot_render_here_is_refused_naming_the_choices(monkeypatch):
    monkeypatch.setattr(variant, "available", lambda: ("llvm_ad_rgb", "scalar_rgb"))
    with pytest.raises(ValueError, match=r"variant 'cuda' cannot render on this machine \(no NVIDIA GPU"):
        variant.prefer("cuda")
    with pytest.raises(ValueError, match=r"variant must be auto, cuda, llvm, scalar or .*llvm_ad_rgb, scalar_rgb.*got 'vulkan'"):
        variant.prefer("vulkan")


@pytest.mark.skipif(backend.device_available("cuda"), reason="this machine has a GPU")
def test_the_command_line_refuses_cuda_without_a_gpu_and_says_what_it_has():
    r = _cli("figures", "--variant", "cuda", "--list")
    assert r.returncode == 2 and "no NVIDIA GPU or driver found" in r.stderr and "llvm_ad_rgb" in r.stderr
    r = _cli("--backend", "cuda", "eval", "lambertian", "--wi", "0,0", "--wo", "0,0")
    assert r.returncode == 2 and "Dr.Jit devices here: llvm" in r.stderr


def test_version_names_the_backends_and_variants_of_this_machine():
    r = _cli("--version")
    assert r.returncode == 0
    lines = r.stdout.splitlines()
    assert lines[0].startswith("plausible, version ")
    assert "numpy" in lines[1] and "llvm (Dr.Jit)" in lines[1]
    assert "llvm_ad_rgb" in lines[2] and f"renders use {variant.preferred('rgb')}" in lines[2]


class _FakeMi:
    def __init__(self, name):
        self.name = name

    def variant(self):
        return self.name


def test_device_exact_turns_fast_math_off_on_cuda_only_and_restores_it():
    before = dr.flag(dr.JitFlag.FastMath)
    with device_exact(_FakeMi("cuda_ad_rgb"), dr):
        assert dr.flag(dr.JitFlag.FastMath) is False
    assert dr.flag(dr.JitFlag.FastMath) == before
    with device_exact(_FakeMi(VARIANT), dr):
        assert dr.flag(dr.JitFlag.FastMath) == (False if VARIANT.startswith("cuda") else before)


def test_a_rendering_figure_records_the_variant_it_ran_on(tmp_path):
    from plausible.figures import report
    from plausible.figures.core import get

    fig = get("as-furnace")
    assert fig.renders and report.render_variant(fig) == variant.preferred("rgb")
    assert report.render_variant(get("neumann-fig1")) is None
    k1 = report.input_key(fig, resolution=None, spp=None, quick=True, src="x")
    old = variant.ENV in os.environ
    assert not old
    try:
        variant.prefer("scalar")
        k2 = report.input_key(fig, resolution=None, spp=None, quick=True, src="x")
    finally:
        variant.prefer(None)
    assert k1 != k2        # another device: the cached figure is made again
    page = report.write_index(tmp_path, {"as-furnace": dict(renders=True, resolution=8, spp=1, status="ok",
                                                            variant="cuda_ad_rgb", params={})})
    assert "variant = cuda_ad_rgb" in page.read_text()
    json.dumps(report.render_variant(fig))
