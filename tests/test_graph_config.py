"""Pipelines built for their configuration (viewer/render/graph/registry.py): the passes, textures
and read-backs of what runs, cached per (mode, configuration), with texture accesses and
read-backs checked while a pipeline runs as host resources are (viewer/render/graph/pool.py)."""
from __future__ import annotations

import numpy as np
import pytest

from viewer.render.graph.params import ParamSet
from viewer.render.modes.hybrid.config import HybridConfig
from viewer.render.modes import MODES
from viewer.render.graph.passes import FullscreenPass, Pass, Pipeline
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.graph.registry import build, mode_config
from viewer.render.renderer import Renderer
from world.loader import load_scene

from conftest import CONFORMANCE

RANGE_PASSES = {"mask_edge_near", "ray_mask"}
PATHS = {"hybrid_path", "hybrid_path2"}


def params(*assignments: str) -> ParamSet:
    p = ParamSet()
    p.apply(list(assignments))
    return p


def names(pipe: Pipeline) -> list[str]:
    return [p.name for p in pipe.passes]


def textures(pipe: Pipeline) -> set[str]:
    return {n for p in pipe.passes for n in (*p.inputs, *p.produces)}


def read_backs(pipe: Pipeline) -> list[tuple[str, str]]:
    return [(r.name, p.name) for r, p in pipe.read_backs()]


def test_default_hybrid_holds_only_what_runs():
    pipe = build("hybrid")
    assert pipe.config == HybridConfig(segments=1, range_check=False, composite="bucket")
    assert names(pipe) == ["gbuffer", "motion_tiles", "select_tiles", "hybrid_tilemax_x",
                           "hybrid_tilemax", "hybrid_neighbormax", "hybrid_neighbormax_read",
                           "mask_displacement", "reveal", "reveal_shade", "hybrid_composite"]
    made = textures(pipe)
    assert not made & (PATHS | {"normal", "mask_edge", "mask_edge_near", "ray_mask_tiles"})
    assert pipe.passes[0].produces == ("color", "hybrid_front")
    # Nothing made that no later pass reads but a pass's own intermediates.
    assert pipe.unread() == ["motion_tiles_x", "static_color", "static_hybrid_front"]
    assert read_backs(pipe) == [("static_raster", "gbuffer"), ("motion_tiles", "select_tiles"),
                                ("hybrid_neighbormax", "hybrid_neighbormax_read"),
                                ("ray_mask", "reveal")]


def test_hybrid_segments_and_range_check_add_their_passes_and_targets():
    four = build("hybrid", params("hybrid.segments=4"))
    assert four.config.segments == 4 and not RANGE_PASSES & set(names(four))
    assert PATHS <= set(four.passes[0].produces)
    assert {"hybrid_neighbormax_path", "hybrid_neighbormax_path2"} <= set(four.passes[-1].inputs)
    # Along a path the composite reads the path's extent back, not NeighborMax.
    assert "hybrid_neighbormax_read" not in names(four)
    assert ("hybrid_neighbormax_path2", "hybrid_composite") in read_backs(four)
    both = build("hybrid", params("hybrid.segments=4", "hybrid.range_check=true"))
    assert RANGE_PASSES <= set(names(both)) and "normal" in both.passes[0].produces
    assert ("mask_edge_ids", "ray_mask") in read_backs(both)
    # The time-sampled composite makes the mask tiles and has no cheaper variants to pick.
    time = build("hybrid", params("hybrid.composite=time"))
    assert "ray_mask_tiles" in time.passes[-1].produces
    assert "hybrid_neighbormax_read" not in names(time)


@pytest.mark.parametrize("mode", ["mcguire", "ue4", "guertin"])
def test_post_process_paths_only_with_segments(mode):
    one, two = build(mode), build(mode, params(f"{mode}.segments=2"))
    assert not textures(one) & PATHS
    assert "hybrid_path" in textures(two) and "hybrid_path2" not in textures(two)
    assert one.config != two.config and mode_config(mode) == one.config


def test_graph_shows_the_configuration_and_counts(capsys):
    from viewer.commands.main import main
    assert main(["graph", "hybrid", "--set", "hybrid.segments=4",
                 "--set", "hybrid.range_check=true"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1] == ("config HybridConfig(segments=4, range_check=True, composite='bucket', "
                      "curve='steps')")
    assert out[2] == "12 passes (10 gpu, 2 cpu); read-backs: 4 every frame, 3 at times"
    assert "  mask_survivors: mask_displacement (most tiles moving)" in out
    assert main(["graph", "hybrid"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[2] == "11 passes (8 gpu, 3 cpu); read-backs: 3 every frame, 1 at times"
    assert main(["graph", "off"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1:3] == ["config NoConfig()", "1 pass (1 gpu, 0 cpu); read-backs: 0 every "
                        "frame, 1 at times"]
    assert main(["graph", "ue4", "--set", "hybrid.segments=2"]) == 2
    assert "mode ue4 does not use the hybrid parameters" in capsys.readouterr().err


def test_renderer_caches_a_pipeline_per_configuration(ctx):
    r = Renderer(ctx, load_scene(CONFORMANCE / "basic.toml"), (64, 36))
    try:
        default = r.pipeline("hybrid")
        # A parameter that changes no pass (read per frame) keeps the pipeline.
        assert r.pipeline("hybrid", params("hybrid.samples_max=32")) is default
        four = r.pipeline("hybrid", params("hybrid.segments=4"))
        assert four is not default and four is r.pipeline("hybrid", params("hybrid.segments=4"))
        r.render("hybrid", 0.0, params("hybrid.segments=4"))
        assert PATHS <= set(r.buffers())
        # The default frame after it: its buffers are its own pipeline's, in its order,
        # whatever the pool still holds of the other configuration's.
        r.render("hybrid", 0.0)
        assert list(r.buffers()) == default.textures() and not PATHS & set(r.buffers())
        r.render("hybrid", 0.0, params("motion.steps=2"))
        assert list(r.buffers()) == default.textures() + ["motion_steps_sum"]
        # A pipeline run with the parameters of another configuration is refused.
        frame = r.frame(0.0, params("hybrid.range_check=true"))
        with pytest.raises(RuntimeError, match="built for HybridConfig"):
            default.run(frame)
    finally:
        r.release()


OUT = TexSpec(4, "f4")


class Source(FullscreenPass):
    name, fragment, produces = "source", "passes/accumulate.frag", ("a", "b")

    def outputs(self, frame):
        return {n: OUT for n in self.produces}

    def execute(self, frame):
        for n in self.produces:
            frame.pool.clear((n,), (1.0, 0.0, 0.0, 1.0))


class Copy(FullscreenPass):
    """Draws `into` from `source`, declaring only input "a" and output "c"."""
    name, fragment, inputs, produces = "copy", "passes/accumulate.frag", ("a",), ("c",)

    def __init__(self, source="a", into="c"):
        self.source, self.into = source, into

    def outputs(self, frame):
        return {"c": OUT}

    def execute(self, frame):
        self.draw(frame, (self.into,), {"u_src": self.source}, {"u_weight": 1.0})


class ReadsBack(Pass):
    name, runs_on, inputs = "reads", "cpu", ("a",)

    def __init__(self, declared: bool):
        self.reads_back = (ReadBack("a"),) if declared else ()

    def execute(self, frame):
        frame.stats["a"] = frame.read("a")


def test_undeclared_texture_reads_and_writes_raise(synthetic_frame):
    run = lambda *passes: Pipeline("x", [Source(), *passes], output="a").run(  # noqa: E731
        synthetic_frame((8, 4)))
    run(Copy())
    with pytest.raises(RuntimeError, match="pass copy reads texture b, which it does not "
                                           "declare in inputs"):
        run(Copy(source="b"))
    with pytest.raises(RuntimeError, match="pass copy writes texture b, which it does not "
                                           "declare in produces"):
        run(Copy(into="b"))
    # an input is never written: drawn into, cleared (even when clean), uploaded
    for write in (lambda f: Copy(into="a").execute(f), lambda f: f.pool.clear(("a",)),
                  lambda f: f.write("a", np.zeros((4, 8, 4), np.float32)),
                  lambda f: f.pool.texture("a", OUT)):
        class Writes(Copy):
            def execute(self, frame, write=write):
                write(frame)
        with pytest.raises(RuntimeError, match="pass copy writes texture a, which it "
                                               "declares as an input"):
            run(Writes())
    # nor declared as both: refused when the pipeline is built
    both = Copy()
    both.produces = ("c", "a")
    with pytest.raises(ValueError, match=r"pass copy both reads and writes \['a'\]"):
        Pipeline("x", [Source(), both], output="a")
    # Outside a pipeline (a pass run on its own) nothing is checked.
    frame = synthetic_frame((8, 4))
    Source().allocate(frame)
    Copy().allocate(frame)
    Copy(source="b", into="b").execute(frame)


def test_read_backs_go_through_declared_passes(synthetic_frame):
    frame = synthetic_frame((8, 4))
    Pipeline("x", [Source(), ReadsBack(True)], output="a").run(frame)
    assert np.array_equal(frame.stats["a"][..., 0], np.ones((4, 8), np.float32))
    with pytest.raises(RuntimeError, match="pass reads reads texture a back to the host, "
                                           "which it does not declare in reads_back"):
        Pipeline("x", [Source(), ReadsBack(False)], output="a").run(synthetic_frame((8, 4)))
    # A declared read-back must be of a texture the pass reads or makes.
    bad = ReadsBack(True)
    bad.reads_back = (ReadBack("b"),)
    with pytest.raises(ValueError, match=r"pass reads reads back \['b'\]"):
        Pipeline("x", [Source(), bad], output="a")


def test_every_mode_runs_under_its_checks(ctx, monkeypatch):
    """Every mode's default frame and the hybrid's other configurations run with every
    texture access and read-back checked (a pass touching what it does not declare
    raises); each read-back the graph lists as every frame's happens, and no other than
    it lists."""
    from viewer.render.graph.pool import ResourcePool
    seen = []
    read_back = ResourcePool.read_back

    def record(pool, name, *args, **kw):
        if pool._pass is not None:          # (not the caller's read of the image)
            seen.append((name, pool._pass.name))
        return read_back(pool, name, *args, **kw)
    monkeypatch.setattr(ResourcePool, "read_back", record)
    r = Renderer(ctx, load_scene(CONFORMANCE / "basic.toml"), (64, 36))
    try:
        for m in MODES:
            r.render(m, 0.0, params("reference.samples=2"))
        for sets in (("hybrid.segments=2", "hybrid.range_check=true"),
                     ("hybrid.segments=4", "hybrid.composite=split"),
                     ("hybrid.composite=time",)):
            seen.clear()
            assert r.render("hybrid", 0.0, params(*sets)).image.any()
            declared = r.pipeline("hybrid", params(*sets)).read_backs()
            every = {(b.name, p.name) for b, p in declared if not b.when}
            assert every <= set(seen) <= {(b.name, p.name) for b, p in declared}, sets
    finally:
        r.release()


@pytest.mark.parametrize("settings", [(), ("hybrid.curve=inverse",), ("motion.steps=2",)])
def test_every_pass_a_frame_times_is_in_the_graph(ctx, capsys, settings):
    """What `hmblur bench` times (a frame's pass_ms: the pipeline's passes and the
    renderer's own work around it) is what `hmblur graph` lists, on a glTF scene whose
    motion bends."""
    from viewer.commands.main import main
    scene = load_scene("rover")
    r = Renderer(ctx, scene, (96, 54))
    try:
        timed = set(r.render("hybrid", scene.render.time, params(*settings),
                             timing=True).pass_ms)
    finally:
        r.release()
    assert main(["graph", "hybrid", *[a for s in settings for a in ("--set", s)]]) == 0
    listed = {line.split(":")[0].split()[0] for line in capsys.readouterr().out.splitlines()
              if line.startswith("  ") and ":" in line}
    assert {"scene_pose", "gbuffer", "hybrid_composite"} <= timed
    assert timed <= listed, timed - listed
    assert ("motion_bend" in listed) == (settings == ())
    assert ("motion_table" in timed) == (settings == ("hybrid.curve=inverse",))
