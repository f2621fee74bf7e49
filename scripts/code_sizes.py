"""Largest modules (lines) and longest functions (lines, def to last line) of the project,
and the longest functions of the render path (viewer/render, raytrace, world).

    python scripts/code_sizes.py [ROOT]        # ROOT: a checkout (default: this one)
"""
import ast
import sys
from pathlib import Path

root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1]
RENDER_PATH = ("viewer/render/", "raytrace/", "world/")
files = [p for d in ("viewer", "raytrace", "world", "glsl", "scripts", "scenes")
         for p in (root / d).rglob("*")
         if p.suffix in (".py", ".frag", ".vert", ".glsl") and "__pycache__" not in p.parts]
mods = sorted(((len(p.read_text().splitlines()), str(p.relative_to(root))) for p in files),
              reverse=True)
print("largest modules:")
for n, p in mods[:10]:
    print(f"  {n:5d} {p}")
funcs = []
for p in files:
    if p.suffix != ".py":
        continue
    tree = ast.parse(p.read_text())
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            funcs.append((node.end_lineno - node.lineno + 1,
                          f"{p.relative_to(root).as_posix()}:{node.lineno} {node.name}"))
funcs.sort(reverse=True)
print("longest functions:")
for n, f in funcs[:10]:
    print(f"  {n:5d} {f}")
print("longest functions of the render path (viewer/render, raytrace, world):")
for n, f in [x for x in funcs if x[1].startswith(RENDER_PATH)][:5]:
    print(f"  {n:5d} {f}")
print(f"total lines {sum(n for n, _ in mods)} in {len(mods)} files (tests excluded)")
tests = list((root / "tests").glob("*.py"))
print(f"tests: {sum(len(p.read_text().splitlines()) for p in tests)} lines in {len(tests)} files")
