"""The docs name only files that exist: every project path written in README.md and
docs/*.md (and in the comments of the code and shaders) is a file or folder of this
checkout, and docs/architecture.md's map of folders lists the groups of
tests/test_imports.py's LAYERS in their order. A moved file fails here until the text that
names it moves with it. The README and docs/performance.md stay short enough to read."""
from __future__ import annotations

import re
from pathlib import Path

from test_imports import LAYERS

ROOT = Path(__file__).resolve().parents[1]
TOP = ("hybrid_mblur", "viewer", "world", "raytrace", "glsl", "scenes", "scripts", "tests",
       "docs/examples")
PATH = re.compile(r"(?<![\w./-])((?:" + "|".join(TOP) + r")/[\w./*-]*)")
SOURCES = ("*.py", "*.frag", "*.vert", "*.glsl", "*.sh")


def paths_in(text: str) -> set[str]:
    """The project paths written in `text` (a trailing full stop or colon is prose)."""
    return {m.rstrip(".,:;") for m in PATH.findall(text)}


def missing(paths) -> list[str]:
    return sorted(p for p in paths
                  if not (any(ROOT.glob(p.rstrip("/"))) if "*" in p else (ROOT / p).exists()))


def test_path_finder_reads_prose_and_markdown():
    text = ("See `viewer/render/graph/passes.py`, glsl/passes/ and world/x.py. Not foo/viewer/a.py "
            "nor a.viewer/b; (raytrace/kernels.py): viewer/commands/*.py")
    assert paths_in(text) == {"viewer/render/graph/passes.py", "glsl/passes/", "world/x.py",
                              "raytrace/kernels.py", "viewer/commands/*.py"}
    assert missing(paths_in(text)) == ["world/x.py"]


def test_every_path_the_docs_name_exists():
    found = {}
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for p in missing(paths_in(doc.read_text())):
            found.setdefault(p, []).append(doc.name)
    assert found == {}


def test_every_path_the_code_comments_name_exists():
    found = {}
    for top in ("hybrid_mblur", "viewer", "world", "raytrace", "glsl", "scripts", "docs/examples"):
        files = [f for pattern in SOURCES for f in sorted((ROOT / top).rglob(pattern))]
        assert files, f"{top}/ holds no source to read: a folder renamed here goes unchecked"
        for f in files:
            for p in missing(paths_in(f.read_text())):
                found.setdefault(p, []).append(str(f.relative_to(ROOT)))
    assert found == {}


def folder_group(cell: str) -> str:
    """`viewer/render/modes/` -> viewer.render.modes, `viewer/__main__.py` -> viewer.__main__,
    `viewer/__init__.py` -> viewer."""
    name = cell.strip("`").rstrip("/").removesuffix(".py").replace("/", ".")
    return name.removesuffix(".__init__")


def test_the_architecture_map_lists_the_import_layers_in_order():
    text = (ROOT / "docs" / "architecture.md").read_text()
    section = text.split("## Layers", 1)[1].split("\n## ", 1)[0]
    table = [line for line in section.splitlines() if line.startswith("|")]
    assert table[0].startswith("| group |")
    rows = [line.split(" | ")[0].lstrip("| ") for line in table[2:]]
    groups = [tuple(folder_group(c) for c in re.findall(r"`[^`]+`", row)) for row in rows]
    assert groups == [tuple(row) for row in LAYERS]


def test_the_readme_and_the_performance_page_stay_short():
    # Details go to docs/*.md (docs/commands.md for what each command writes); the format
    # and algorithm references may be as long as they need.
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 200
    assert len((ROOT / "docs" / "performance.md").read_text().splitlines()) <= 250
    setup = readme.split("## Set-up on a fresh machine", 1)[1].split("\n## ", 1)[0]
    assert [line.strip() for line in setup.splitlines() if line.startswith("    ")] == [
        "bash scripts/demo.sh", "bash scripts/test.sh"]
