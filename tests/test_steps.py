"""Sub-exposure steps (`motion.steps`, viewer/render/steps.py): N = 1 is the plain frame,
N sub-frames are the mean of N frames of shutter s/N rendered on their own at the
sub-interval centres, the error against the reference falls as N grows, and the
parameter is checked like any other."""
import numpy as np
import pytest

from viewer.commands.main import main
from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODE_GROUPS
from viewer.render.renderer import Renderer
from viewer.render.steps import step_seed, sub_exposures
from viewer.render.timing import PassClock
from world.loader import load_scene

from conftest import CONFORMANCE

SIZE = (64, 36)
STEPPED = [m for m, groups in MODE_GROUPS.items() if "motion" in groups]


def steps(n: int) -> ParamSet:
    p = ParamSet()
    p.set("motion.steps", n)
    return p


@pytest.fixture(scope="module")
def spinner():
    from conftest import _context
    ctx = _context()
    scene = load_scene("spinner")
    for light in scene.lights:       # brighter than 1 in places: a clamp before the mean shows
        light.color = light.color * 2.5
    r = Renderer(ctx, scene, SIZE)
    yield r
    r.release()


# The CLI first: a shot makes a GL context of its own current, and the module's renderer
# (below) must be made and released while the shared context is current.

@pytest.mark.parametrize("value, needle", [("0", "at least 1"), ("2.5", "expected int"),
                                           ("many", "expected int"), ("1000", "at most")])
def test_bad_steps_exit_2_with_one_line(tmp_path, capsys, value, needle):
    out = tmp_path / "o.png"
    code = main(["shot", str(CONFORMANCE / "basic.toml"), "--size", "16x9",
                 "--set", f"motion.steps={value}", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "motion.steps" in err[0] and needle in err[0]
    assert not out.exists()


def test_steps_reach_the_sidecar(tmp_path, capsys):
    import json
    out = tmp_path / "o.png"
    assert main(["shot", str(CONFORMANCE / "basic.toml"), "--size", "16x9", "--mode",
                 "mcguire", "--set", "motion.steps=2", "--out", str(out)]) == 0
    side = json.loads(out.with_suffix(".json").read_text())
    assert side["params"]["motion"] == {"steps": 2, "curve_px": 1.0}
    assert side["params"]["mcguire"]["curve_steps"] == 1
    assert main(["shot", str(CONFORMANCE / "basic.toml"), "--size", "16x9", "--mode", "off",
                 "--out", str(out)]) == 0
    assert "motion" not in json.loads(out.with_suffix(".json").read_text())["params"]
    # off takes no steps: setting them there is a mistake, not a silent no-op
    capsys.readouterr()
    assert main(["shot", str(CONFORMANCE / "basic.toml"), "--size", "16x9", "--mode", "off",
                 "--set", "motion.steps=2", "--out", str(out)]) == 2
    assert "motion" in capsys.readouterr().err


def test_every_real_time_mode_takes_steps_and_off_and_reference_do_not():
    assert {"mcguire", "ue4", "hybrid"} <= set(STEPPED)
    assert "motion" not in MODE_GROUPS["off"]
    assert "motion" not in MODE_GROUPS["reference"]


def test_sub_exposures_are_the_centres_of_n_equal_parts_with_distinct_seeds():
    t, s = 0.3, 0.08
    subs = sub_exposures(t, s, 5, 4)
    edges = np.linspace(t - s / 2, t + s / 2, 5)
    np.testing.assert_allclose([x[0] for x in subs], (edges[:-1] + edges[1:]) / 2,
                               rtol=0, atol=1e-15)
    assert [x[1] for x in subs] == [s / 4] * 4
    assert [x[2] for x in subs] == [20, 21, 22, 23]
    assert sub_exposures(t, s, 5, 1) == [(t, s, 5)]          # N = 1: the frame itself
    # Two seeds' sub-frames never share a seed.
    assert not {step_seed(5, 4, k) for k in range(4)} & {step_seed(6, 4, k) for k in range(4)}


def test_one_step_is_the_plain_pipeline(spinner):
    r = spinner
    t = r.scene.render.time
    for mode in STEPPED:
        res = r.render(mode, t, steps(1), seed=3)
        pipe = r.pipeline(mode)                  # the pipeline run by hand, no steps code
        frame = r.frame(t, ParamSet(), 3)
        pipe.run(frame)
        assert np.array_equal(res.image, frame.read(pipe.output)[..., :3]), mode
        assert "steps" not in res.stats


def test_n_steps_are_the_mean_of_n_renders_at_the_sub_interval_centres(spinner):
    r, n, seed = spinner, 3, 2
    t, s = r.scene.render.time, r.scene.camera.shutter
    for mode in STEPPED:
        res = r.render(mode, t, steps(n), seed=seed)
        total = np.zeros_like(res.image)
        try:
            r.scene.camera.shutter = s / n
            for k in range(n):
                tk = t - s / 2 + (k + 0.5) * s / n
                sub = r.render(mode, tk, ParamSet(), seed=seed * n + k).image
                total = total + sub * np.float32(1.0 / n)
                if k:
                    assert not np.array_equal(sub, last), (mode, k)   # the frames move
                last = sub
        finally:
            r.scene.camera.shutter = s
        assert total.max() > 1.5, mode                 # averaged unclamped
        np.testing.assert_allclose(res.image, total, rtol=1e-6, atol=1e-7, err_msg=mode)
        assert res.stats["steps"] == n


def test_steps_approach_the_reference_on_a_rotating_scene(spinner):
    r = spinner
    t = r.scene.render.time
    p = ParamSet()
    p.set("reference.samples", 64)
    ref = r.render("reference", t, p).image
    for mode in STEPPED:
        mse = [float(np.mean((r.render(mode, t, steps(n)).image - ref) ** 2))
               for n in (1, 2, 4)]
        # Measured at 64x36: each doubling cuts it by 1.7-4x (mcguire 3.1e-3, 8.0e-4, 2.3e-4).
        assert mse[1] < 0.8 * mse[0] and mse[2] < 0.8 * mse[1], (mode, mse)


def test_the_timed_loop_renders_the_same_steps(spinner):
    """PassClock.render (the viewer, `hmblur bench`'s pass times) takes the steps too."""
    r = spinner
    t = r.scene.render.time
    for mode in STEPPED:
        want = r.render(mode, t, steps(4), seed=1)
        frame = PassClock(r.ctx, "cpu").render(r, mode, t, steps(4), 1)
        assert np.array_equal(frame.read(r.pipeline(mode).output)[..., :3], want.image), mode
        assert frame.time == t and frame.shutter == r.scene.camera.shutter
        assert frame.pass_ms["motion_steps"] > 0
        assert frame.stats["steps"] == 4


def test_state_kept_across_frames_survives_the_sub_frames(spinner):
    """A frame after a stepped one (the hybrid's kept tiles, static layer, poses) is the
    frame a fresh renderer makes."""
    r = spinner
    t = r.scene.render.time
    for mode in STEPPED:
        r.render(mode, t + 0.01, steps(4))
        after = r.render(mode, t, ParamSet()).image
        fresh = Renderer(r.ctx, r.scene, SIZE)
        try:
            assert np.array_equal(after, fresh.render(mode, t, ParamSet()).image), mode
        finally:
            fresh.release()


def test_hybrid_counters_are_summed_over_the_steps(spinner):
    r = spinner
    t = r.scene.render.time
    one = r.render("hybrid", t, steps(1)).stats
    four = r.render("hybrid", t, steps(4)).stats
    assert four["tiles"] == 4 * one["tiles"]           # the tile grid, once a sub-frame
    assert four["rays"] == four["masked_pixels"] > 0


def test_reference_and_off_ignore_steps(spinner):
    r = spinner
    t = r.scene.render.time
    for mode in ("off", "reference"):
        p = ParamSet()
        p.set("reference.samples", 4)
        base = r.render(mode, t, p).image
        p.set("motion.steps", 4)
        assert np.array_equal(r.render(mode, t, p).image, base), mode
