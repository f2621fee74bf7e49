"""Host-side resources declared like textures (viewer/render/graph/host.py), state kept across
frames in the renderer (viewer/render/graph/kept.py), and the pipeline graph that shows both."""
from __future__ import annotations

import numpy as np
import pytest

from viewer.render.graph.params import ParamSet
from viewer.render.graph.host import HostResource, HostResources
from viewer.render.graph.kept import KeptSlot, KeptState
from viewer.render.modes import MODES
from viewer.render.graph.passes import Pass, Pipeline
from viewer.render.graph.registry import build
from viewer.render.modes.hybrid.mask import SurfaceTests
from viewer.render.modes.reference import REGIONS
from viewer.render.renderer import Renderer
from viewer.render.modes.hybrid.reveal import MASKED_PIXELS
from viewer.render.passes.tile_runs import kept_tile_list
from viewer.render.modes.hybrid.tile_select import MotionTiles, SelectTiles
from world.loader import load_scene

from conftest import CONFORMANCE

GBUFFER = ("hybrid_front", "normal", "hybrid_path", "hybrid_path2")   # what they read of it

# What each host resource of the hybrid with the range check is made by and read by,
# written from the passes' roles (module docs of tile_lists, hybrid/composite, hybrid/mask,
# hybrid/reveal).
HYBRID_HOST = {
    "tile_lists": ("TileLists", "select_tiles",
                   "hybrid_tilemax_x, mask_displacement, mask_edge_near, ray_mask, hybrid_composite"),
    "neighbormax": ("ndarray", "hybrid_neighbormax_read", "hybrid_composite"),
    "edge_probe_tiles": ("ndarray | None", "mask_displacement", "mask_edge_near"),
    "survivor_tiles": ("ndarray | None", "mask_displacement", "ray_mask"),
    "masked_pixels": ("ndarray", "reveal", "hybrid_composite"),
    "reveal_hits": ("LayerHits | None", "reveal", "reveal_shade"),
    "reveal_batch": ("dict", "reveal", "the caller"),
}
RANGE_ONLY = {"edge_probe_tiles", "survivor_tiles"}    # (the mask's range check)


def range_check_pipeline():
    p = ParamSet()
    p.set("hybrid.range_check", True)
    return build("hybrid", p)


def test_hybrid_describe_lists_host_resources_with_producer_and_readers():
    text = range_check_pipeline().describe()
    head, table = text.split("\nhost resources:\n")
    rows = table.splitlines()
    assert rows == [f"  {name} ({kind}): {made} -> {read}"
                    for name, (kind, made, read) in HYBRID_HOST.items()]
    # The CPU nodes are marked, and a pass line shows the host resources it reads / makes.
    cpu = [line.split()[0] for line in head.splitlines() if "(cpu)" in line]
    assert cpu == ["select_tiles", "hybrid_neighbormax_read", "reveal"]
    assert "  select_tiles (cpu): motion_tiles -> host:tile_lists" in head.splitlines()
    # No host resource passes for a texture any more.
    textures = {n for p in range_check_pipeline().passes for n in (*p.inputs, *p.produces)}
    assert not textures & set(HYBRID_HOST)
    # Without the range check its passes and their host resources are not in the graph.
    text = MODES["hybrid"]().describe()
    assert not any(f"  {n} (" in text for n in RANGE_ONLY) and "mask_edge_near" not in text


def test_reference_describe_shows_regions_for_the_caller():
    assert MODES["reference"]().describe().endswith(
        "host resources:\n  regions (ndarray): reference -> the caller")
    assert "host resources" not in MODES["mcguire"]().describe()


def test_pipeline_rejects_a_host_resource_not_produced_before_its_reader():
    # The surface tests read the tile lists: without select_tiles before them, the check
    # fails when the pipeline is built, naming the pass and the resource.
    with pytest.raises(ValueError, match=r"pass mask_displacement needs host resources "
                                         r"\['tile_lists'\]"):
        Pipeline("x", [MotionTiles(), SurfaceTests()], output="ray_mask",
                 produced=GBUFFER)
    # Made after its reader is not made before it.
    with pytest.raises(ValueError, match="needs host resources"):
        Pipeline("x", [MotionTiles(), SurfaceTests(), SelectTiles()], output="ray_mask",
                 produced=GBUFFER)
    Pipeline("x", [MotionTiles(), SelectTiles(), SurfaceTests()], output="ray_mask",
             produced=GBUFFER)


LIST = HostResource("numbers", list, "a test resource")


class Maker(Pass):
    name, runs_on, host_outputs = "maker", "cpu", (LIST,)

    def __init__(self, value=None):
        self.value = [1, 2] if value is None else value

    def execute(self, frame):
        frame.host.put(LIST, self.value)


class Reader(Pass):
    name, host_inputs = "reader", (LIST,)

    def execute(self, frame):
        frame.stats["read"] = frame.host[LIST]


class Sneak(Pass):
    name = "sneak"                          # reads LIST without declaring it

    def execute(self, frame):
        frame.host.get(LIST)


def test_host_resources_checked_while_a_pipeline_runs(synthetic_frame):
    with pytest.raises(ValueError, match=r"host resource numbers is made by both maker and maker"):
        Pipeline("x", [Maker(), Maker()], output="numbers_out", produced=("numbers_out",))
    frame = synthetic_frame((8, 4))
    Pipeline("x", [Maker(), Reader()], output="t", produced=("t",)).run(frame)
    assert frame.stats["read"] == [1, 2] and frame.host.names() == ["numbers"]
    # An undeclared read, or a value of another type, is an error at once.
    with pytest.raises(RuntimeError, match="pass sneak reads host resource numbers"):
        Pipeline("x", [Maker(), Sneak()], output="t", produced=("t",)).run(synthetic_frame((8, 4)))
    with pytest.raises(TypeError, match="host resource numbers: expected list, got tuple"):
        Pipeline("x", [Maker((1, 2))], output="t", produced=("t",)).run(synthetic_frame((8, 4)))
    # Outside a pipeline a pass finds only what was put (here: nothing).
    alone = HostResources()
    assert alone.get(LIST) is None and LIST not in alone
    with pytest.raises(KeyError, match="numbers was not produced this frame"):
        alone[LIST]


def test_kept_state_is_typed_and_released():
    class Thing:
        released = 0

        def release(self):
            self.released += 1
    slot = KeptSlot("thing", Thing)
    kept = KeptState()
    assert kept.get(slot) is None
    a = kept.put(slot, Thing())
    with pytest.raises(TypeError, match="kept state thing: expected Thing, got int"):
        kept.put(slot, 3)
    b = kept.put(slot, Thing())                 # the old value is released when replaced
    assert (a.released, b.released) == (1, 0) and kept.get(slot) is b
    kept.release()
    assert b.released == 1 and kept.names() == []


def test_kept_state_makes_a_value_once_and_again_where_it_no_longer_fits():
    class Thing:
        def __init__(self, owner):
            self.owner, self.released = owner, 0

        def release(self):
            self.released += 1
    slot, kept, made = KeptSlot("thing", Thing), KeptState(), []

    def make(owner):
        made.append(Thing(owner))
        return made[-1]
    a = kept.get_or_make(slot, lambda: make("ctx 1"), lambda t: t.owner == "ctx 1")
    assert kept.get_or_make(slot, lambda: make("ctx 1"), lambda t: t.owner == "ctx 1") is a
    b = kept.get_or_make(slot, lambda: make("ctx 2"), lambda t: t.owner == "ctx 2")
    assert b is not a and kept.get(slot) is b and a.released == 1 and len(made) == 2
    assert kept.get_or_make(slot, lambda: make("any")) is b         # no fits: any value


def test_renderer_owns_the_kept_state_and_frames_carry_only_declared_results(ctx):
    r = Renderer(ctx, load_scene(CONFORMANCE / "basic.toml"), (64, 36))
    try:
        res = r.render("hybrid", 0.0)
        assert {"hybrid_reveal", "tile_lists"} <= set(r.kept.names())
        # The frame's results are exactly the hybrid's declared host resources.
        assert sorted(res.host.names()) == sorted(set(HYBRID_HOST) - RANGE_ONLY)
        assert res.stats["masked_pixels"] == len(res.host[MASKED_PIXELS]) > 0
        # Request flags are frame fields: regions only where asked for.
        p = ParamSet()
        p.set("reference.samples", 2)
        plain = r.render("reference", 0.0, p)
        with pytest.raises(KeyError, match="regions was not produced"):
            plain.host[REGIONS]
        calls = []
        rec = r.render("reference", 0.0, p, record_visibility=True,
                       progress=lambda k, n: calls.append((k, n)))
        assert rec.host[REGIONS].shape == (36, 64) and rec.host[REGIONS].dtype == np.uint8
        assert calls == [(0, 2), (1, 2)]
        frame = r.frame(0.0, p, record_visibility=True)
        assert frame.kept is r.kept and frame.record_visibility and frame.progress is None
        # A named list kept across frames is the same list in the next frame.
        first = kept_tile_list(frame, "test_list")
        assert kept_tile_list(r.frame(0.1, p), "test_list") is first
        assert "test_list" in r.kept.names()
    finally:
        r.release()
    assert r.kept.names() == []
