"""The old path of :mod:`plausible.arrays.backend` (issue 33 moved it into ``arrays/``), an alias
kept for the branches in flight that still import ``plausible.backend``: the same module object,
so monkeypatching either name patches both.  Import ``plausible.arrays.backend``; remove this
once no branch uses the old name."""

import sys

from .arrays import backend as _module

sys.modules[__name__] = _module
