"""The floors of the package (issue 33), checked by ``scripts/layers.py``.

The truth is the rule of the design: no import cycle, a module imports only what lies below it,
no function over 80 lines, a library error names arguments (not the CLI's flags), and one owner
of ``"material:"``, no branch on a parameter kind's name outside params.py. The checker is
shown to fail on a small package broken in each way.
"""

from __future__ import annotations

import importlib.util
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("layers", ROOT / "scripts" / "layers.py")
layers = sys.modules["layers"] = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(layers)

REPORT = layers.check(ROOT / "src" / "plausible")

@pytest.mark.parametrize("what", ["cycles", "floors", "long_functions", "flags", "material", "kinds"])
def test_plausible_keeps_its_floors(what):
    assert getattr(REPORT, what) == [], REPORT.text()


def _package(tmp_path, files: dict) -> Path:
    for name, text in files.items():
        f = tmp_path / "pkg" / name
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(textwrap.dedent(text))
    return tmp_path / "pkg"


CLEAN = {
    "__init__.py": "from . import vec\n",
    "vec.py": "import math\n",
    "bxdf.py": "from .vec import math\n",
    "models/__init__.py": "",
    "models/a.py": "from ..bxdf import math\nfrom pkg import vec\n",
    "analysis/__init__.py": "from ..models import a\n",
    "cli.py": "def main():\n    raise SystemExit('use --help')\n",
}


def test_a_clean_package_passes(tmp_path):
    rep = layers.check(_package(tmp_path, CLEAN))
    assert rep.ok(), rep.text()


def test_a_cycle_through_a_function_level_import_is_found(tmp_path):
    files = dict(CLEAN, **{"vec.py": "def f():\n    from .models import a\n"})
    rep = layers.check(_package(tmp_path, files))
    assert rep.cycles == [["pkg.bxdf", "pkg.models.a", "pkg.vec"]]


def test_a_model_importing_analysis_is_an_upward_import(tmp_path):
    files = dict(CLEAN, **{"models/b.py": "def f():\n    from pkg.analysis import a\n"})
    rep = layers.check(_package(tmp_path, files))
    assert rep.floors == ["pkg/models/b.py:2 pkg.models.b imports pkg.analysis"]


def test_the_vector_math_importing_the_contract_is_an_upward_import(tmp_path):
    files = dict(CLEAN, **{"warps.py": "from .bxdf import math\n"})
    assert layers.check(_package(tmp_path, files)).floors == ["pkg/warps.py:1 pkg.warps imports pkg.bxdf"]


def test_a_function_of_81_lines_is_too_long(tmp_path):
    body = "def f():\n" + "    x = 1\n" * 79 + "    return x\n"
    files = dict(CLEAN, **{"long.py": body, "short.py": body.replace("    x = 1\n", "", 1)})
    assert layers.check(_package(tmp_path, files)).long_functions == ["pkg/long.py:1 f (81 lines)"]


def test_a_flag_in_a_library_error_is_found(tmp_path):
    files = dict(CLEAN, **{"lib.py": "def f(x):\n    raise ValueError(f'give --mitsuba-xml, got {x}')\n"})
    assert layers.check(_package(tmp_path, files)).flags == ["pkg/lib.py:2 --mitsuba-xml"]


def test_material_specs_outside_the_catalogue_package_are_found(tmp_path):
    files = dict(CLEAN, **{"registry.py": '"""material:NAME in a docstring is fine."""\n'
                                          'def f(s):\n    if not s:\n        raise ValueError("give material:NAME")\n'
                                          '    return s.startswith("material:")\n',
                           "catalogue/__init__.py": 'PREFIX = "material:"\n'})
    assert layers.check(_package(tmp_path, files)).material == ["pkg/registry.py:5"]


def test_a_branch_on_a_parameter_kind_outside_params_is_found(tmp_path):
    files = dict(CLEAN, **{"params.py": 'def f(p):\n    return p.kind == "color"\n',
                           "plugin.py": 'def g(p, v):\n    if p.kind in ("scalar", "color"):\n        return 1\n'
                                        '    return v.dtype.kind == "f" or p.kind in TABLE or "model" != p.kind\n'})
    assert layers.check(_package(tmp_path, files)).kinds == [
        "pkg/plugin.py:2 p.kind in ('scalar', 'color')", "pkg/plugin.py:4 'model' != p.kind"]
