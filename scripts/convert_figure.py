"""Write docs/images/convert.png: the report's section ``convert-legacy`` (legacy MTL materials,
their conversions to Mitsuba and the rule of thumb; ``src/plausible/figures/conversion.py``).

    PYTHONPATH=src python scripts/convert_figure.py

The same figure is made by ``plausible figures --only convert-legacy``, with its checks.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

from plausible.figures import Context
from plausible.figures.conversion import convert_legacy


def main(out="docs/images/convert.png"):
    with tempfile.TemporaryDirectory() as d:
        ctx = Context(Path(d))
        convert_legacy(ctx, "")
        shutil.copyfile(Path(d) / "convert-legacy.png", out)
    failed = [m["quantity"] for m in ctx.measurements if m.get("ok") is False]
    for m in ctx.measurements:
        print(f"{'ok  ' if m.get('ok') else ('FAIL' if m.get('ok') is False else '    ')} {m['quantity']}: "
              f"{m['measured']:.4g} {m.get('note', '')}")
    print(f"wrote {out}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
