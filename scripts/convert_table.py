"""Write the error table of docs/convert.md: every published fit converted to Mitsuba and glTF.

    PYTHONPATH=src nice -n 19 python scripts/convert_table.py              # run (resumes), then the markdown
    PYTHONPATH=src python scripts/convert_table.py --limit 0               # rewrite the markdown only

The same as ``plausible convert-table --out docs/convert-table.jsonl --markdown
docs/convert-table.md`` (:mod:`plausible.conversion.table`): rows are appended to
``docs/convert-table.jsonl`` as they finish, so an interrupted run resumes where it stopped.
"""

from __future__ import annotations

import sys

from plausible.cli import main

if __name__ == "__main__":
    main(["convert-table", "--out", "docs/convert-table.jsonl", "--markdown", "docs/convert-table.md", *sys.argv[1:]])
