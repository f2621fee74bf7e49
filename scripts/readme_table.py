"""The README's performance table from docs/perf/*.json (scripts/bench_all.sh writes them),
printed as Markdown: one row per scene and size, the animated ratio beside the 640x360
rows. `python scripts/perf_tables.py` writes the same table into README.md's
`<!-- perf:readme -->` block; the table itself is perf_tables.readme_table.

    python scripts/readme_table.py [FOLDER]
"""
from __future__ import annotations

import sys
from pathlib import Path

from perf_tables import PERF, load, readme_table


def main(folder: str | None = None) -> int:
    paths = sorted(Path(folder).glob("*.json")) if folder else sorted(PERF.glob("*.json"))
    print(readme_table(load(paths)))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
