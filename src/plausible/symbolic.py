"""The old path of :mod:`plausible.arrays.symbolic` (issue 33 moved it into ``arrays/``), an alias
kept for the branches in flight that still import ``plausible.symbolic``: the same module object,
so monkeypatching either name patches both.  Import ``plausible.arrays.symbolic``; remove this
once no branch uses the old name."""

import sys

from .arrays import symbolic as _module

sys.modules[__name__] = _module
