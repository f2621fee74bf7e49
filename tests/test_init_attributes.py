"""Every attribute an object of viewer/ or raytrace/ holds is made in its class's __init__
(or declared on the class, or made by a base class's __init__): a reader finds all of an
object's state in one place, and no method reads an attribute that a call it depends on
may not have made yet."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _self_targets(node) -> list[str]:
    """The self.X names an assignment statement writes."""
    out = []

    def walk(t):
        if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name) and t.value.id == "self":
            out.append(t.attr)
        elif isinstance(t, (ast.Tuple, ast.List)):
            for e in t.elts:
                walk(e)
        elif isinstance(t, ast.Starred):
            walk(t.value)
    if isinstance(node, ast.Assign):
        for t in node.targets:
            walk(t)
    elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
        walk(node.target)
    return out


def classes_of(paths, root: Path = ROOT) -> dict:
    """[(name, where, made in __init__ or on the class, {attribute: [method]} made
    elsewhere, base class names)] of every class in `paths`."""
    out = []
    for p in paths:
        tree = ast.parse(p.read_text())
        for cls in ast.walk(tree):
            if not isinstance(cls, ast.ClassDef):
                continue
            made, elsewhere = set(), {}
            for node in cls.body:
                if isinstance(node, (ast.Assign, ast.AnnAssign)):
                    for t in node.targets if isinstance(node, ast.Assign) else [node.target]:
                        if isinstance(t, ast.Name):
                            made.add(t.id)
                if isinstance(node, ast.FunctionDef):
                    for sub in ast.walk(node):
                        for a in _self_targets(sub):
                            if node.name == "__init__":
                                made.add(a)
                            else:
                                elsewhere.setdefault(a, []).append(node.name)
            bases = [b.id if isinstance(b, ast.Name) else getattr(b, "attr", "") for b in cls.bases]
            out.append((cls.name, f"{p.relative_to(root)}:{cls.lineno}", made, elsewhere, bases))
    return out


def late_attributes(classes: list) -> list[str]:
    """The attributes made outside __init__ that no __init__ of the class or its bases
    makes, nor the class declares (bases by name among `classes`: any of that name)."""
    by_name: dict[str, list] = {}
    for c in classes:
        by_name.setdefault(c[0], []).append(c)

    def made(c, seen=()):
        own, bases = c[2], c[4]
        return own.union(*(made(b, seen + (c[0],)) for name in bases if name not in seen
                           for b in by_name.get(name, ())))
    late = []
    for c in classes:
        name, where, _, elsewhere, _ = c
        late += [f"{where} {name}.{a} (made in {', '.join(sorted(set(methods)))})"
                 for a, methods in sorted(elsewhere.items()) if a not in made(c)]
    return late


def test_attributes_are_made_in_init():
    paths = [p for d in ("viewer", "raytrace") for p in sorted((ROOT / d).rglob("*.py"))]
    classes = classes_of(paths)
    assert len(classes) > 50                      # the scan found the project's classes
    assert late_attributes(classes) == []


def test_the_scan_finds_an_attribute_made_late(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("class A:\n    x = 0\n    def __init__(self):\n        self.y = 1\n"
                 "    def f(self):\n        self.x, self.y, self.z = 1, 2, 3\n"
                 "class B(A):\n    def g(self):\n        self.y = self.w = 4\n")
    classes = classes_of([p], tmp_path)
    assert [(c[0], c[2], c[4]) for c in classes] == [("A", {"x", "y"}, []), ("B", set(), ["A"])]
    assert late_attributes(classes) == ["m.py:1 A.z (made in f)", "m.py:7 B.w (made in g)"]
