"""The GLSL preprocessor: include-once, defines after #version, errors as file:line."""
import pytest

from viewer.render.graph.shaders import LINE_BASE, ShaderError, build_program, preprocess


@pytest.fixture
def glsl_dir(tmp_path):
    (tmp_path / "a.glsl").write_text("#include \"b.glsl\"\nfloat a() { return b() + 1.0; }\n")
    (tmp_path / "b.glsl").write_text("float b() { return VALUE; }\n")
    (tmp_path / "main.frag").write_text(
        "#version 330 core\n#include \"a.glsl\"\n#include \"b.glsl\"\n"
        "out vec4 c;\nvoid main() { c = vec4(a()); }\n")
    (tmp_path / "bad.frag").write_text(
        "#version 330 core\n#include \"b.glsl\"\nout vec4 c;\n\nvoid main() { c = undefined_thing; }\n")
    return tmp_path


def test_include_once_and_defines_after_version(glsl_dir):
    src = preprocess("main.frag", {"VALUE": 2.5}, root=glsl_dir)
    lines = src.text.splitlines()
    assert lines[0] == "#version 330 core"
    assert lines[1] == "#define VALUE 2.5"
    assert src.text.count("float b()") == 1           # included twice, pasted once
    assert src.files == ["main.frag", "a.glsl", "b.glsl"]
    assert src.locate(3 * LINE_BASE + 1) == "b.glsl:1"


def test_compile_error_names_file_and_line(ctx, glsl_dir):
    (glsl_dir / "v.vert").write_text("#version 330 core\nvoid main() { gl_Position = vec4(0.0); }\n")
    with pytest.raises(ShaderError) as err:
        build_program(ctx, "v.vert", "bad.frag", {"VALUE": 1.0}, root=glsl_dir)
    assert "bad.frag:5" in str(err.value)
    assert "undefined_thing" in str(err.value)
    ctx.error  # a failed compile may leave a GL error behind; consume it


def test_missing_include_is_reported(glsl_dir):
    (glsl_dir / "m.frag").write_text("#version 330 core\n#include \"nope.glsl\"\n")
    with pytest.raises(ShaderError, match="nope.glsl"):
        preprocess("m.frag", root=glsl_dir)


def test_shipped_shaders_compile(ctx):
    from world.conventions import glsl_defines
    from viewer.render.passes.gbuffer import LAYOUTS, layout_defines
    from viewer.render.graph.gpu_scene import TEX_KINDS
    kinds = {f"TEX_{k.upper()}": v for k, v in TEX_KINDS.items() if k}
    for layout in LAYOUTS:
        for in_texture in (0, 1):
            lights = {"MAX_LIGHTS": 16, "LIGHTS_TEXTURE": in_texture, "LIGHTS_PER_ROW": 1024,
                      **kinds}
            build_program(ctx, "passes/gbuffer.vert", "passes/gbuffer.frag",
                          {**glsl_defines(), **lights, **layout_defines(layout)}).release()
