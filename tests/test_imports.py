"""The project's modules import downward only: no two modules reach each other through
imports (top-level or inside functions, under TYPE_CHECKING too), the scene model
(world) imports neither renderer, the ray tracer never imports the viewer, and the render
core never imports the window, the CLI or the windowing libraries."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("world", "raytrace", "viewer", "glsl", "scenes")


def modules() -> dict[str, Path]:
    found = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join(parts)] = path
    return found


def imports(name: str, path: Path, known: dict) -> set[str]:
    """Project modules that `name` imports anywhere in its file, with the packages that
    Python runs first to reach them (importing a.b.c runs a.b's __init__), except the
    packages holding `name` itself (already being imported when it runs)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    targets = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                head = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(head + ([base] if base else []))
            targets += [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base
                        for a in node.names]
    own = {".".join(name.split(".")[:k]) for k in range(1, name.count(".") + 2)}
    out = set()
    for t in targets:
        while t and t not in known:
            t = t.rpartition(".")[0]
        parts = t.split(".") if t else []
        out |= {m for m in (".".join(parts[:k]) for k in range(1, len(parts) + 1))
                if m in known and m not in own}
    return out


def graph() -> dict[str, set[str]]:
    known = modules()
    return {n: imports(n, p, known) for n, p in known.items()}


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in g[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(g):
        if v not in index:
            visit(v)
    return out


def test_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_imports_resolve_relative_and_function_level_imports(tmp_path):
    (tmp_path / "pkg" / "sub").mkdir(parents=True)
    files = {"pkg/__init__.py": "from . import a\n",
             "pkg/a.py": "def f():\n    from .sub import b as kernels\n",
             "pkg/sub/__init__.py": "",
             "pkg/sub/b.py": "from .. import a\nfrom ..a import f\nimport numpy\n"}
    for rel, text in files.items():
        (tmp_path / rel).write_text(text)
    known = {"pkg": tmp_path / "pkg/__init__.py", "pkg.a": tmp_path / "pkg/a.py",
             "pkg.sub": tmp_path / "pkg/sub/__init__.py", "pkg.sub.b": tmp_path / "pkg/sub/b.py"}
    g = {n: imports(n, p, known) for n, p in known.items()}
    # pkg.a reaches pkg.sub.b through pkg.sub's __init__; pkg.sub.b's own packages are
    # being imported when it runs.
    assert g == {"pkg": {"pkg.a"}, "pkg.a": {"pkg.sub", "pkg.sub.b"}, "pkg.sub": set(),
                 "pkg.sub.b": {"pkg.a"}}
    assert cycles(g) == [["pkg.a", "pkg.sub.b"]]
    # A package whose __init__ reaches back to a module importing one of its modules.
    (tmp_path / "pkg/sub/__init__.py").write_text("from . import c\n")
    (tmp_path / "pkg/sub/b.py").write_text("")
    (tmp_path / "pkg/sub/c.py").write_text("from .. import a\n")
    known["pkg.sub.c"] = tmp_path / "pkg/sub/c.py"
    g = {n: imports(n, p, known) for n, p in known.items()}
    assert cycles(g) == [["pkg.a", "pkg.sub", "pkg.sub.c"]]


def test_every_package_is_scanned():
    names = set(graph())
    for pkg in PACKAGES:
        assert pkg in names, pkg
    assert {"world.loader", "raytrace.kernels", "viewer.render.modes", "viewer.ui.panel"} <= names


def test_no_import_cycles():
    found = cycles(graph())
    assert not found, "modules importing each other: " + "; ".join(" <-> ".join(c) for c in found)


# The layers, top first: a module imports only from its own group and the groups below
# it. Groups on one row are peers that do not import each other. docs/architecture.md's
# map of folders lists the same groups in this order (tests/test_docs_paths.py).
LAYERS = (
    ("viewer.__main__",),
    ("viewer.commands",),                 # one module per subcommand
    ("viewer.sweep",),                    # hmblur sweep on Dask
    ("viewer.eval", "viewer.ui"),         # metrics, strips, plots | the window
    ("viewer.io",),                       # files out: images, sidecars, video, signals
    ("viewer.cli",),                      # the commands' argument toolkit
    ("viewer.render",),                   # the render core's front: Renderer, steps, timing
    ("viewer.render.modes",),             # each mode; the hybrid's package
    ("viewer.render.passes",),            # passes shared by modes
    ("viewer.render.graph",),             # the framework: passes, pool, frame, registry
    ("viewer.glcontext",),                # the headless EGL context
    ("viewer",),                          # the package itself (its docstring)
    ("raytrace",),                        # Embree scenes and the reveal's rays
    ("world",),                           # scene model, loaders, camera, conventions
    ("glsl", "scenes"),                   # shader sources, built-in scene files
)


def layer_of(module: str) -> tuple[int, str]:
    """(row, group) of the longest group that holds `module`."""
    best = None
    for row, groups in enumerate(LAYERS):
        for g in groups:
            if module == g or module.startswith(g + "."):
                if best is None or len(g) > len(best[1]):
                    best = (row, g)
    assert best is not None, f"{module} is in no layer: add its group to LAYERS"
    return best


def _upward(m: str, t: str) -> bool:
    (rm, gm), (rt, gt) = layer_of(m), layer_of(t)
    return rt < rm or (rt == rm and gt != gm)


def test_layer_rule_on_hand_made_pairs():
    assert _upward("viewer.render.graph.pool", "viewer.render.passes.depth")
    assert _upward("viewer.ui.state", "viewer.commands.shot")
    assert _upward("viewer.eval.strip", "viewer.ui.panel")            # peers
    assert _upward("world.loader", "raytrace.kernels")
    assert not _upward("viewer.render.modes.mcguire", "viewer.render.passes.tiles")
    assert not _upward("viewer.commands.shot", "world.loader")
    assert not _upward("viewer.render.modes.hybrid.mask", "viewer.render.modes.hybrid.tile_select")


def test_every_module_is_in_a_layer():
    for m in graph():
        layer_of(m)


def test_lower_layers_do_not_import_upper_ones():
    g = graph()
    upward = sorted((m, t) for m, ts in g.items() for t in ts if _upward(m, t))
    assert not upward, "upward imports: " + "; ".join(f"{m} -> {t}" for m, t in upward)


def test_render_core_and_lower_layers_never_import_the_window_libraries():
    known = modules()
    found = []
    for name, path in known.items():
        if not name.startswith(("world", "raytrace", "viewer.render")):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            mods = ([a.name for a in node.names] if isinstance(node, ast.Import)
                    else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level
                    else [])
            found += [(name, m) for m in mods if m.split(".")[0] in ("glfw", "imgui_bundle")]
    assert found == []
