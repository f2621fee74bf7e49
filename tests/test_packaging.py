"""The wheel carries the shaders, the built-in scenes and their assets, so an installed
`hmblur` works outside a checkout."""
import subprocess
import sys
import zipfile

from conftest import ROOT


def test_wheel_contains_code_shaders_and_scenes(tmp_path):
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "-q", "-w", str(tmp_path), str(ROOT)], check=True, capture_output=True)
    wheel = next(tmp_path.glob("hybrid_mblur-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    need = {"viewer/commands/main.py", "viewer/render/renderer.py", "viewer/render/passes/gbuffer.py",
            "raytrace/embree_scene.py", "world/loader.py", "world/scene.py",
            "world/camera.py", "viewer/render/modes/hybrid/pipeline.py", "glsl/passes/gbuffer.frag",
            "glsl/passes/shading.glsl",
            "glsl/graph/fullscreen.vert", "scenes/living_room.toml",
            "hybrid_mblur/__init__.py", "hybrid_mblur/renderer.py",
            "viewer/render/modes/user/pipeline.py", "scenes/assets/painting.png",
            "scenes/assets/quad_uv.obj", "scenes/rover.toml", "scenes/assets/rover.glb"}
    assert need <= names, need - names
    for folder in ("glsl", "scenes"):
        shipped = {n.split("/", 1)[1] for n in names if n.startswith(folder + "/")}
        on_disk = {p.relative_to(ROOT / folder).as_posix()
                   for p in (ROOT / folder).rglob("*")
                   if p.is_file() and p.suffix in {".glsl", ".frag", ".vert", ".toml", ".png", ".obj",
                                         ".glb"}}
        assert on_disk <= shipped, on_disk - shipped
    assert not any(n.startswith("tests/") for n in names)
    entry = [n for n in names if n.endswith("entry_points.txt")]
    text = zipfile.ZipFile(wheel).read(entry[0]).decode()
    assert "hmblur = viewer.commands.main:main" in text
