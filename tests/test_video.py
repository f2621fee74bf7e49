"""`hmblur video`: every format written and readable, a single mode's PNG frame equal to
`hmblur shot`'s, the sidecar reproducing the video, metrics and flicker against an
independent computation, and bad input exiting 2 with nothing left behind."""
from __future__ import annotations

import csv
import json
import os

import av
import flip_evaluator
import numpy as np
import pytest
from PIL import Image

from conftest import CONFORMANCE, ROOT
from viewer.commands.main import main
from viewer.eval.plot import line_plots, nice_ticks, tick_label
from viewer.eval.temporal import flicker
from viewer.io.video_writer import gif_durations

BASIC = str(CONFORMANCE / "basic.toml")
SMALL = ["--size", "64x36", "--frames", "3"]


def video(tmp_path, out, *args):
    # --samples only where the reference is drawn (it is refused elsewhere)
    modes = args[args.index("--modes") + 1].split(",") if "--modes" in args else []
    samples = ["--samples", "4"] if "reference" in modes or "--metrics" in args else []
    assert main(["video", BASIC, *SMALL, *samples, "--out", str(tmp_path / out), *args]) == 0
    return tmp_path / out


def pngs(folder):
    return sorted(p.name for p in folder.glob("frame_*.png"))


def listing(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


# --- formats -----------------------------------------------------------------------------------

def test_each_format_is_written_and_reads_back(tmp_path):
    folder = video(tmp_path, "frames/", "--modes", "off,mcguire")
    assert pngs(folder) == ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
    first = np.asarray(Image.open(folder / "frame_0000.png").convert("RGB"))
    h, w = first.shape[:2]
    assert w > 2 * 64 and h > 36                    # two labelled panels
    assert json.loads((folder / "video.json").read_text())["format"] == "png"

    mp4 = video(tmp_path, "new/folder/clip.mp4", "--modes", "off,mcguire")
    with av.open(str(mp4)) as c:
        stream = c.streams.video[0]
        assert stream.codec_context.name == "h264"
        decoded = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
    assert len(decoded) == 3
    # 4:2:0 needs even sides: an odd side gets its last row / column repeated
    assert decoded[0].shape == (h + h % 2, w + w % 2, 3)
    # lossy (4:2:0 chroma, CRF 18), but the colours come back with the same matrix and
    # range (BT.709, limited): a range mix-up would take whites ~20 codes off
    back = decoded[0][:h, :w].astype(int)
    err = np.abs(back - first)
    assert np.median(err) <= 3, np.median(err)
    white = (first == 255).all(axis=2)
    assert white.sum() > 500 and back[white].mean() > 252
    assert (tmp_path / "new" / "folder" / "clip.json").is_file()   # (missing folders made)

    gif = video(tmp_path, "clip.gif", "--modes", "off,mcguire")
    with Image.open(gif) as g:
        assert g.n_frames == 3 and g.size == (w, h)
        g.seek(0)
        assert np.abs(np.asarray(g.convert("RGB")).astype(int) - first).mean() < 3.0
    leftovers = [p for p in tmp_path.rglob("*") if p.name.startswith(".")
                 and p.name != ".hmblur-outputs.json"]      # (hmblur's list of its files)
    assert leftovers == []


def test_gif_delays_keep_the_clip_length():
    d = gif_durations(24, 24.0)
    assert sum(d) == 1000 and set(d) == {40, 50}
    assert gif_durations(3, 10.0) == [100, 100, 100]


# --- frames are shots ----------------------------------------------------------------------------

@pytest.mark.parametrize("mode", ["ue4", "reference"])
def test_a_single_mode_frame_is_the_shot_of_that_time(tmp_path, mode):
    folder = video(tmp_path, "v", "--modes", mode, "--start", "0.1", "--fps", "10", "--seed", "3")
    for k in (0, 2):
        shot = tmp_path / f"s{k}.png"
        samples = ["--samples", "4"] if mode == "reference" else []   # (shot takes it there only)
        assert main(["shot", BASIC, "--mode", mode, "--size", "64x36", *samples,
                     "--seed", "3", "--time", repr(0.1 + k / 10), "--out", str(shot)]) == 0
        assert (folder / f"frame_{k:04d}.png").read_bytes() == shot.read_bytes()
    # a shot's sidecar animates that shot: its mode, time, size and seed
    assert main(["video", "--params", str(tmp_path / "s2.json"), "--frames", "1",
                 "--out", str(tmp_path / "from_shot")]) == 0
    assert (tmp_path / "from_shot" / "frame_0000.png").read_bytes() == (tmp_path / "s2.png").read_bytes()
    # and the frames move: frame 2 is not frame 0
    assert (folder / "frame_0000.png").read_bytes() != (folder / "frame_0002.png").read_bytes()


def test_the_sidecar_reproduces_the_video_from_another_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    rel = os.path.relpath(BASIC, ROOT)
    assert main(["video", rel, "--modes", "mcguire,off", "--size", "48x30", "--frames", "2",
                 "--start", "0.05", "--fps", "30", "--seed", "5",
                 "--set", "blur.max_radius=0.05", "--out", str(tmp_path / "a")]) == 0
    side = json.loads((tmp_path / "a" / "video.json").read_text())
    assert side["scene"] == BASIC and side["modes"] == ["mcguire", "off"]
    assert (side["frames"], side["fps"], side["time"], side["seed"]) == (2, 30.0, 0.05, 5)
    monkeypatch.chdir(tmp_path)
    assert main(["video", "--params", "a/video.json", "--out", "b"]) == 0
    assert pngs(tmp_path / "b") == pngs(tmp_path / "a") == ["frame_0000.png", "frame_0001.png"]
    for name in pngs(tmp_path / "a"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    # a flag given overrides the sidecar
    assert main(["video", "--params", "a/video.json", "--frames", "1", "--out", "c"]) == 0
    assert pngs(tmp_path / "c") == ["frame_0000.png"]
    assert (tmp_path / "c" / "frame_0000.png").read_bytes() == (tmp_path / "a" / "frame_0000.png").read_bytes()
    # a built-in scene is stored as shot's sidecar stores it: its name beside its file
    assert main(["video", "spinner", "--modes", "off", "--size", "32x18", "--frames", "1",
                 "--out", str(tmp_path / "d")]) == 0
    side = json.loads((tmp_path / "d" / "video.json").read_text())
    assert side["scene_builtin"] == "spinner" and side["scene"] == str(ROOT / "scenes" / "spinner.toml")
    assert main(["video", "--params", "d/video.json", "--out", "e"]) == 0
    assert (tmp_path / "e" / "frame_0000.png").read_bytes() == (tmp_path / "d" / "frame_0000.png").read_bytes()


def test_a_shorter_clip_into_the_same_folder_leaves_no_stale_frames(tmp_path):
    video(tmp_path, "v", "--modes", "off")
    assert main(["video", BASIC, "--size", "64x36", "--frames", "1", "--modes", "off",
                 "--out", str(tmp_path / "v")]) == 0
    assert pngs(tmp_path / "v") == ["frame_0000.png"]


# --- metrics and flicker ---------------------------------------------------------------------------

REGION_COLOURS = {"static": (40, 40, 40), "inner": (230, 60, 40), "outer": (40, 110, 230)}


def test_metrics_match_an_independent_computation_from_shots(tmp_path):
    """Per frame: `compare` of that time gives the mode's and the reference's PNGs and the
    region map; PSNR, FLIP and flicker are recomputed from those pixels with numpy and
    flip_evaluator directly."""
    folder = video(tmp_path, "v", "--modes", "mcguire", "--metrics")
    rows = list(csv.DictReader(open(folder / "metrics.csv")))
    assert [r["region"] for r in rows[:4]] == ["all", "static", "inner", "outer"]
    assert len(rows) == 3 * 4 and {r["mode"] for r in rows} == {"mcguire"}
    tests, refs, regions = [], [], []
    for k in range(3):
        d = tmp_path / f"c{k}"
        assert main(["compare", BASIC, "--size", "64x36", "--samples", "4", "--modes", "mcguire",
                     "--time", repr(k / 24), "--out", str(d)]) == 0
        t = np.asarray(Image.open(d / "mcguire.png").convert("RGB"))
        r = np.asarray(Image.open(d / "reference.png").convert("RGB"))
        pic = np.asarray(Image.open(d / "regions.png").convert("RGB"))[: t.shape[0]]  # (key below)
        region = np.full(t.shape[:2], -1)
        for code, name in enumerate(("static", "inner", "outer")):
            region[(pic == REGION_COLOURS[name]).all(axis=2)] = code
        assert (region >= 0).all()
        tests.append(t), refs.append(r), regions.append(region)
        err = flip_evaluator.evaluate(r.astype(np.float32) / 255, t.astype(np.float32) / 255,
                                      "LDR", applyMagma=False)[0][..., 0]
        for name, mask in (("all", region >= 0), ("static", region == 0),
                           ("inner", region == 1), ("outer", region == 2)):
            row = next(x for x in rows if int(x["frame"]) == k and x["region"] == name)
            assert int(row["pixels"]) == mask.sum()
            if not mask.any():
                assert row["flip"] == "" and row["psnr"] == ""
                continue
            mse = ((t[mask] / 255.0 - r[mask] / 255.0) ** 2).mean()
            assert float(row["psnr"]) == pytest.approx(10 * np.log10(1 / mse), rel=1e-9)
            assert float(row["flip"]) == pytest.approx(err[mask].mean(), rel=1e-5)
    assert regions[0].max() > 0                      # the scene has blur regions at all
    # flicker, from the formula in docs/video.md
    fl = {r["region"]: r for r in csv.DictReader(open(folder / "flicker.csv"))}
    for name, code in (("all", None), ("inner", 1)):
        per_pair = []
        for k in range(2):
            mask = (np.ones(regions[k].shape, bool) if code is None
                    else (regions[k] == code) | (regions[k + 1] == code))
            d = (tests[k + 1].astype(int) - tests[k]) - (refs[k + 1].astype(int) - refs[k])
            per_pair.append(np.abs(d).mean(axis=2)[mask].mean())
        assert float(fl[name]["flicker"]) == pytest.approx(np.mean(per_pair), rel=1e-9)
        assert int(fl[name]["pairs"]) == 2
    side = json.loads((folder / "video.json").read_text())
    assert side["flicker"]["mcguire"]["all"]["flicker"] == pytest.approx(float(fl["all"]["flicker"]))
    plot = np.asarray(Image.open(folder / "flip.png").convert("RGB"))
    assert plot.shape[0] > 300 and plot.shape[1] > 600


def test_flicker_of_a_constant_error_is_zero():
    rng = np.random.default_rng(1)
    ref = [rng.integers(0, 200, (4, 5, 3), dtype=np.uint8) for _ in range(4)]
    offset = rng.integers(0, 50, (4, 5, 3), dtype=np.uint8)
    out = flicker([r + offset for r in ref], ref)
    assert out["all"]["flicker"] == 0.0 and out["all"]["pairs"] == 3
    still = np.full((4, 5, 3), 7, np.uint8)
    assert flicker([still] * 3, [still] * 3)["all"]["flicker"] == 0.0


def test_flicker_of_a_known_sequence():
    """2x1 pixels, one channel shown (all three alike). Reference constant; the mode's
    left pixel goes 0 -> 10 -> 0, right pixel 0 -> 0 -> 30. Pair 0: |10|, |0| -> mean 5;
    pair 1: |-10|, |30| -> 20; flicker = (5 + 20) / 2 = 12.5. Region 'inner' = the right
    pixel in frame 0 only, then the left in frame 2: pair 0 (union {right}) gives 0,
    pair 1 (union {left}) gives 10 -> 5; 'outer' is empty in every frame -> None."""
    def img(a, b):
        return np.array([[[a] * 3, [b] * 3]], np.uint8)
    seq = [img(0, 0), img(10, 0), img(0, 30)]
    ref = [img(0, 0)] * 3
    regions = [np.array([[0, 1]]), np.array([[0, 0]]), np.array([[1, 0]])]
    out = flicker(seq, ref, regions)
    assert out["all"]["flicker"] == 12.5
    assert out["inner"]["flicker"] == 5.0 and out["inner"]["pairs"] == 2
    assert out["outer"] == {"flicker": None, "change": None, "reference_change": None, "pairs": 0}
    assert out["all"]["change"] == 12.5 and out["all"]["reference_change"] == 0.0
    # the reference's own change is not flicker: mode == reference gives 0
    assert flicker(seq, seq, regions)["all"]["flicker"] == 0.0


def test_plot_ticks_are_round_and_the_plot_has_one_colour_per_series():
    assert nice_ticks(0.0, 0.27) == [0.0, 0.1, 0.2, 0.3]
    assert nice_ticks(0.0, 0.02) == [0.0, 0.005, 0.01, 0.015, 0.02]
    assert nice_ticks(0.0, 1.0) == [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    ticks = nice_ticks(-0.5, 0.46)
    assert [tick_label(v, ticks) for v in ticks] == ["-0.6", "-0.4", "-0.2", "0.0", "0.2", "0.4", "0.6"]
    red, blue = (214, 39, 40), (31, 119, 180)
    img = line_plots([("a", {"x": ([0, 1], [0.1, 0.2]), "y": ([0, 1], [0.3, None])})],
                     {"x": red, "y": blue}, "t", "v")
    px = img.reshape(-1, 3)
    assert (px == red).all(axis=1).sum() > 100 and (px == blue).all(axis=1).sum() > 10


# --- bad input ----------------------------------------------------------------------------------

def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys):
    (tmp_path / "afile").write_text("x")
    (tmp_path / "dir.mp4").mkdir()
    (tmp_path / "side").mkdir()
    (tmp_path / "side" / "clip.json").mkdir()        # where clip.mp4's sidecar would go
    cases = {
        "unknown extension": (["--out", str(tmp_path / "v.avi")], "unknown extension '.avi'"),
        "a .png path": (["--out", str(tmp_path / "v.png")], "folder"),
        "zero frames": (["--frames", "0", "--out", str(tmp_path / "v.mp4")], "--frames"),
        "fps zero": (["--fps", "0", "--out", str(tmp_path / "v.mp4")], "--fps"),
        "fps negative": (["--fps", "-24", "--out", str(tmp_path / "v.mp4")], "--fps"),
        "fps nan": (["--fps", "nan", "--out", str(tmp_path / "v.mp4")], "--fps"),
        "a folder that is a file": (["--out", str(tmp_path / "afile")], "not a folder"),
        "a file that is a folder": (["--out", str(tmp_path / "dir.mp4")], "directory"),
        "sidecar path is a folder": (["--out", str(tmp_path / "side" / "clip.mp4")], "clip.json"),
        "unknown mode": (["--modes", "off,fancy", "--out", str(tmp_path / "v.mp4")], "'fancy'"),
        "mode twice": (["--modes", "off,off", "--out", str(tmp_path / "v.mp4")], "twice"),
        "bad start": (["--start", "soon", "--out", str(tmp_path / "v.mp4")], "--time 'soon'"),
        "metrics of the reference alone": (["--modes", "reference", "--metrics", "--out",
                                            str(tmp_path / "v.mp4")], "--metrics"),
    }
    before = listing(tmp_path)
    for name, (argv, needle) in cases.items():
        assert main(["video", BASIC, "--size", "16x9", *argv]) == 2, name
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and needle in err[0], (name, err)
    assert main(["video", "--out", str(tmp_path / "v.mp4")]) == 2
    assert "SCENE" in capsys.readouterr().err
    # the viewer's recording checks its path and rate before it opens a window
    for argv, needle in ((["--record", str(tmp_path / "r.avi")], "--record"),
                         (["--record", str(tmp_path / "r.mp4"), "--record-fps", "0"], "--record-fps")):
        assert main(["view", BASIC, *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and needle in err[0], err
    assert listing(tmp_path) == before


def test_a_failure_mid_video_leaves_no_file(tmp_path, capsys, monkeypatch):
    from viewer.render.renderer import Renderer
    real, calls = Renderer.render, []

    def failing(self, *a, **kw):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(self, *a, **kw)
    monkeypatch.setattr(Renderer, "render", failing)
    for out in ("v.mp4", "v.gif", "frames"):
        calls.clear()
        assert main(["video", BASIC, "--size", "16x9", "--frames", "4", "--modes", "off",
                     "--out", str(tmp_path / out)]) == 130
    assert listing(tmp_path) == []


# --- the viewer records ----------------------------------------------------------------------------

def test_the_viewer_records_what_it_animates_and_video_reproduces_it(tmp_path):
    """`hmblur view --record` of a playing animation: one frame per displayed frame, 1/fps
    of scene time apart; `hmblur video --params` of its sidecar renders the same frames
    (to the window's rounding: the viewer draws through its own context)."""
    import subprocess
    import sys
    from tests.xvfb import Xvfb
    x = Xvfb().start()
    try:
        script = tmp_path / "s.txt"
        script.write_text("0 play\n0 panel off\n")
        cmd = [sys.executable, "-m", "viewer", "view", BASIC, "--mode", "mcguire",
               "--size", "96x64", "--frames", "4", "--record", str(tmp_path / "rec"),
               "--record-fps", "12", "--script", str(script)]
        p = subprocess.run(cmd, cwd=ROOT, env=x.env(), capture_output=True, text=True, timeout=240)
        assert p.returncode == 0, p.stderr
    finally:
        x.stop()
    rec = tmp_path / "rec"
    assert pngs(rec) == [f"frame_{k:04d}.png" for k in range(4)]
    side = json.loads((rec / "video.json").read_text())
    assert side["modes"] == ["mcguire"] and side["frames"] == 4 and side["fps"] == 12.0
    assert side["time"] == pytest.approx(1 / 12)       # played one step before the first frame
    assert main(["video", "--params", str(rec / "video.json"), "--out", str(tmp_path / "again")]) == 0
    for name in pngs(rec):
        a = np.asarray(Image.open(rec / name).convert("RGB")).astype(int)
        b = np.asarray(Image.open(tmp_path / "again" / name).convert("RGB")).astype(int)
        assert a.shape == b.shape == (64, 96, 3)
        assert np.abs(a - b).mean() < 0.5, name
    first, last = (np.asarray(Image.open(rec / n)).astype(int) for n in (pngs(rec)[0], pngs(rec)[-1]))
    assert np.abs(first - last).mean() > 0.5          # the animation moved


def test_the_printed_size_is_the_files(tmp_path, capsys):
    # An odd-sided frame: the MP4 holds it rounded up to even sides, and says so; a GIF
    # and PNG frames hold it as it is.
    import re
    for out in ("odd.mp4", "odd.gif", "odd"):
        assert main(["video", BASIC, "--size", "65x37", "--frames", "2", "--modes", "off",
                     "--out", str(tmp_path / out)]) == 0
        printed = re.search(r" (\d+)x(\d+) \(off\)", capsys.readouterr().out).groups()
        if out.endswith(".mp4"):
            with av.open(str(tmp_path / out)) as c:
                held = next(c.decode(video=0)).to_ndarray(format="rgb24").shape
        elif out.endswith(".gif"):
            with Image.open(tmp_path / out) as g:
                held = g.size[::-1]
        else:
            held = np.asarray(Image.open(tmp_path / out / "frame_0000.png")).shape
        assert (int(printed[1]), int(printed[0])) == tuple(held[:2]), out
    assert printed == ("65", "37")
