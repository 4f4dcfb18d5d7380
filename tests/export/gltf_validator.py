"""The Khronos glTF validator (npm ``gltf-validator``, installed by ``make gltf-validator``
into ``.cache/npm``) run on a file by node: its report's ``issues``."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR = ROOT / ".cache" / "npm" / "node_modules" / "gltf-validator"

_SCRIPT = """
const validator = require(process.argv[1]);
const fs = require('fs');
const nodePath = require('path');
const path = process.argv[2];
// external resources (images referenced by URI) are read relative to the file, as the validator's README does
const externalResourceFunction = (uri) => new Promise((resolve, reject) => {
  fs.readFile(nodePath.resolve(nodePath.dirname(path), decodeURIComponent(uri)),
              (err, data) => err ? reject(err.toString()) : resolve(new Uint8Array(data)));
});
validator.validateBytes(new Uint8Array(fs.readFileSync(path)),
                        {uri: path, format: 'gltf', maxIssues: 200, externalResourceFunction})
  .then(r => process.stdout.write(JSON.stringify(r)))
  .catch(e => { process.stderr.write(String(e)); process.exit(2); });
"""


def pinned_version() -> str:
    return re.search(r"^GLTF_VALIDATOR_VERSION\s*:=\s*(\S+)", (ROOT / "Makefile").read_text(), re.M).group(1)


def missing(why):
    if os.environ.get("CI"):
        pytest.fail(why)
    pytest.skip(why)


def require():
    """Skip (fail on CI) unless node and the pinned validator are installed."""
    if shutil.which("node") is None:
        missing("node is not installed (make gltf-validator installs npm, which brings it)")
    pkg = VALIDATOR / "package.json"
    if not pkg.exists() or json.loads(pkg.read_text())["version"] != pinned_version():
        missing(f"gltf-validator {pinned_version()} is not installed in {VALIDATOR.parent} "
                f"(make gltf-validator installs it)")


def validate(path) -> dict:
    """The validator's report of ``path`` (``report["issues"]``: ``numErrors``, ``numWarnings``,
    ``messages`` with ``code`` and ``pointer``); images referenced by URI are read relative to
    ``path`` and validated too (a missing one is an ``IO_ERROR``)."""
    require()
    out = subprocess.run(["node", "-e", _SCRIPT, str(VALIDATOR), str(path)], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)
