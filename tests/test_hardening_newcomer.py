"""The first steps a newcomer takes: set-up that waits for apt's lock and installs only
what changed, a warm-up that leaves no kernel of any mode to compile, `shot` and `view` on
the hybrid, help and docs that list every mode and scene, and FLIP maps with the strip's
inset."""
from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from conftest import CONFORMANCE, ROOT
from viewer.cli import args as cliargs
from viewer.commands import compare as cmd_compare
from viewer.commands.main import main
from viewer.render.modes import MODES
from viewer.eval.strip import GAP, error_strip, heat, make_strip
from world.errors import UserError
from world.loader import builtin_scene_names

BASIC = str(CONFORMANCE / "basic.toml")

# Every numba dispatcher of the kernel modules and the signatures it holds (compiled or
# loaded from the cache): after the warm-up, rendering every mode must add none.
PROBE = textwrap.dedent("""
    import importlib, json, sys
    from numba.core.registry import CPUDispatcher
    MODULES = ["raytrace.kernels", "viewer.render.passes.tile_kernels",
               "viewer.render.modes.hybrid.reveal_kernels", "world.camera"]
    def signatures():
        out = {}
        for m in MODULES:
            for k, v in vars(importlib.import_module(m)).items():
                if isinstance(v, CPUDispatcher) and v.py_func.__module__ == m:
                    out[f"{m}.{k}"] = sorted(map(str, v.signatures))
        return out
    from viewer.cli.warmup import warm_up
    warm_up()
    before = signatures()
    from viewer.glcontext import create_headless
    from viewer.render.graph.params import ParamSet
    from viewer.render.modes import MODES, MODE_GROUPS
    from viewer.render.renderer import Renderer
    from world.loader import builtin_scene_names, builtin_scene_path, load_scene
    ctx = create_headless()
    scenes = [builtin_scene_path(n) for n in builtin_scene_names()] + [sys.argv[1]]
    for path in scenes:
        scene = load_scene(path)
        r = Renderer(ctx, scene, (80, 45))
        for mode in MODES:
            for segments in (1, 2):
                p = ParamSet()
                p.set("reference.samples", 3)
                if segments > 1 and mode in MODE_GROUPS and mode in ("mcguire", "ue4",
                                                                       "guertin", "hybrid"):
                    p.set(f"{mode}.segments", segments)
                r.render(mode, scene.render.time + 0.01, p, seed=3)
        r.release()
    after = signatures()
    print(json.dumps({k: v for k, v in after.items() if v != before.get(k)}))
""")


def test_the_warm_up_leaves_no_kernel_of_any_mode_to_compile():
    p = subprocess.run([sys.executable, "-c", PROBE, BASIC], cwd=ROOT, capture_output=True,
                       text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout.strip().splitlines()[-1]) == {}


def test_shot_and_view_default_to_the_hybrid(tmp_path):
    assert cliargs.pick_mode(None, None, MODES) == "hybrid"
    assert cliargs.pick_mode(None, {"mode": "ue4"}, MODES) == "ue4"        # a sidecar's mode
    assert cliargs.pick_mode("off", {"mode": "ue4"}, MODES) == "off"       # the flag wins
    with pytest.raises(UserError, match="--mode blur: expected one of off, "):
        cliargs.pick_mode("blur", None, MODES)
    out = tmp_path / "a.png"
    assert main(["shot", BASIC, "--size", "64x36", "--out", str(out)]) == 0
    side = json.loads(out.with_suffix(".json").read_text())
    assert side["mode"] == "hybrid"
    assert side["timing"]["first_frame"] is True and "first frame" in side["timing"]["note"]


def all_scene_names() -> set[str]:
    names = set(builtin_scene_names())
    for folder in (ROOT / "scenes" / "bench", ROOT / "scenes" / "examples", CONFORMANCE,
                   CONFORMANCE / "gltf"):
        names |= {p.stem for p in folder.glob("*.toml")}
    return names


def test_help_lists_every_mode_and_scene(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    text = capsys.readouterr().out
    assert {"basic", "vase_pan", "keys_arc", "shapes", "gltf_box", "first_scene"} <= all_scene_names()
    for name in sorted(MODES) + sorted(all_scene_names()):
        assert name in text, name
    assert "Guertin 2014" in text


def test_the_docs_list_every_mode_and_scene():
    doc = (ROOT / "docs" / "scene-format.md").read_text()
    readme = (ROOT / "README.md").read_text()
    for name in sorted(MODES) + sorted(all_scene_names()):
        assert f"`{name}`" in doc or f"{name}.toml" in doc or f",{name}" in doc, name
        assert name in readme, name


# --- scripts/setup.sh --------------------------------------------------------------------

FAKE = """#!/bin/sh
echo "$(basename "$0") $*" >> "{log}"
{body}
"""


def fake(path, log, body=""):
    path.write_text(FAKE.format(log=log, body=body))
    path.chmod(path.stat().st_mode | stat.S_IXUSR)


def test_setup_waits_for_the_apt_lock_and_installs_only_what_changed(tmp_path):
    # The script in a copy of the tree, with fake dpkg-query (every package missing the
    # first time), apt-get, sudo-less root, and a fake .venv/bin/python recording calls.
    tree, bin_ = tmp_path / "tree", tmp_path / "bin"
    (tree / "scripts").mkdir(parents=True)
    (tree / ".venv" / "bin").mkdir(parents=True)
    bin_.mkdir()
    (tree / "scripts" / "setup.sh").write_text((ROOT / "scripts" / "setup.sh").read_text())
    (tree / "pyproject.toml").write_text((ROOT / "pyproject.toml").read_text())
    log = tmp_path / "calls.log"
    installed = tmp_path / "installed"
    fake(bin_ / "dpkg-query", log, f'[ -e "{installed}" ] && printf "install ok installed"')
    fake(bin_ / "apt-get", log, f'touch "{installed}"')
    fake(bin_ / "id", log, 'echo 0')
    fake(tree / ".venv" / "bin" / "python", log,
         'case "$*" in *sys.version*) echo "3.11.2 (fake)";; esac')
    env = {**os.environ, "PATH": f"{bin_}:{os.environ['PATH']}"}

    def run() -> list[str]:
        log.write_text("")
        p = subprocess.run(["bash", str(tree / "scripts" / "setup.sh")], env=env,
                           capture_output=True, text=True, timeout=60)
        assert p.returncode == 0, p.stderr
        assert p.stdout.strip().splitlines()[-1].startswith(
            "setup: done; the command is .venv/bin/hmblur")
        return log.read_text().splitlines()

    first = run()
    apt = [c for c in first if c.startswith("apt-get")]
    assert len(apt) == 2 and all("-o DPkg::Lock::Timeout=600" in c for c in apt)
    assert any("pip install -q -e .[test]" in c for c in first)
    assert any("-m viewer.cli.warmup" in c for c in first)
    second = run()
    assert not any(c.startswith("apt-get") or "pip install" in c for c in second), second
    assert any("-m viewer.cli.warmup" in c for c in second)
    (tree / "pyproject.toml").write_text((ROOT / "pyproject.toml").read_text() + "\n# changed\n")
    assert any("pip install -q -e .[test]" in c for c in run())


# --- flip.png: the strip's inset ---------------------------------------------------------

def test_the_error_strip_has_the_strips_zoomed_inset():
    rng = np.random.default_rng(5)
    maps = [("a", rng.random((40, 64))), ("b", rng.random((40, 64)))]
    box = (10, 8, 26, 24)                                   # x0, y0, x1, y1: 16x16 px
    plain, inset = error_strip(maps), error_strip(maps, inset_box=box)
    zoom = 64 // 16
    assert inset.shape[0] == plain.shape[0] + 16 * zoom + GAP
    # the zoomed crop of each map sits where make_strip puts the strip's
    strip = make_strip([(label, heat(m)) for label, m in maps], inset_box=box)
    np.testing.assert_array_equal(inset[:strip.shape[0]], strip)
    crop = np.repeat(np.repeat(heat(maps[0][1])[8:24, 10:26], zoom, 0), zoom, 1)
    assert any(np.array_equal(inset[y:y + 64, 0:64], crop) for y in range(inset.shape[0] - 63))


def test_compare_draws_flip_png_with_the_strips_inset(tmp_path, monkeypatch):
    seen = []
    real = cmd_compare.error_strip
    monkeypatch.setattr(cmd_compare, "error_strip",
                        lambda *a, **k: seen.append(k.get("inset_box")) or real(*a, **k))
    out = tmp_path / "cmp"
    assert main(["compare", BASIC, "--size", "64x36", "--samples", "4", "--modes",
                 "off,hybrid", "--out", str(out)]) == 0
    inset = json.loads((out / "metrics.json").read_text())["inset"]
    assert seen == [tuple(inset)] and inset[2] > inset[0]
