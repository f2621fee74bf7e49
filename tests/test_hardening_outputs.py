"""What hmblur writes: every video format holds its frames in time order (each decoded
frame is the shot of its own time, not of another), a folder of frames keeps the files
hmblur did not write, and the screen-path bend sees the camera's own motion."""
from __future__ import annotations

import json
import math
import textwrap

import av
import numpy as np
import pytest
from PIL import Image

from viewer.commands.main import main
from world.camera import Camera
from world.path_bend import FRACTIONS, screen_bend

from conftest import scene_from

SLIDE = """
    background = [0.1, 0.1, 0.1]
    ambient = [1.0, 1.0, 1.0]
    [camera]
    position = [0.0, 0.0, 5.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 40.0
    [render]
    width = 64
    height = 36
    [[objects]]
    mesh = { box = [0.6, 0.6, 0.1] }
    position = [-1.5, 0.0, 0.0]
    velocity = [1.0, 0.0, 0.0]
    material = { albedo = [0.9, 0.9, 0.9] }
"""
FPS, FRAMES = "1", "4"       # the box at x = -1.5, -0.5, 0.5, 1.5: four distinct frames


def slide(tmp_path):
    p = tmp_path / "slide.toml"
    p.write_text(textwrap.dedent(SLIDE))
    return str(p)


def shots(tmp_path, scene):
    """The image `shot` makes at each frame's time."""
    out = []
    for k in range(int(FRAMES)):
        png = tmp_path / f"shot{k}.png"
        assert main(["shot", scene, "--mode", "off", "--time", str(k / float(FPS)),
                     "--out", str(png)]) == 0
        out.append(np.asarray(Image.open(png).convert("RGB")).astype(float))
    return out


def nearest_shots(frames, reference):
    """For each decoded frame, the index of the shot it is closest to."""
    return [int(np.argmin([np.abs(f[:r.shape[0], :r.shape[1]] - r).mean() for r in reference]))
            for f in frames]


@pytest.mark.parametrize("suffix", [".mp4", ".gif", ""])
def test_every_format_holds_its_frames_in_time_order(tmp_path, suffix):
    scene = slide(tmp_path)
    reference = shots(tmp_path, scene)
    out = tmp_path / f"clip{suffix}"
    assert main(["video", scene, "--modes", "off", "--frames", FRAMES, "--fps", FPS,
                 "--out", str(out)]) == 0
    if suffix == ".mp4":
        with av.open(str(out)) as c:
            frames = [f.to_ndarray(format="rgb24").astype(float) for f in c.decode(video=0)]
    elif suffix == ".gif":
        with Image.open(out) as g:
            frames = []
            for k in range(g.n_frames):
                g.seek(k)
                frames.append(np.asarray(g.convert("RGB")).astype(float))
    else:
        frames = [np.asarray(Image.open(out / f"frame_{k:04d}.png").convert("RGB")).astype(float)
                  for k in range(int(FRAMES))]
    assert nearest_shots(frames, reference) == list(range(int(FRAMES)))


# --- a folder of frames is the user's: only hmblur's own files are replaced ----------------

def test_a_folder_with_the_users_own_frames_is_refused_and_kept(tmp_path, capsys):
    scene = slide(tmp_path)
    photos = tmp_path / "photos"
    photos.mkdir()
    mine = {f"frame_{k:04d}.png": f"holiday {k}".encode() for k in range(2, 10)}
    for name, data in mine.items():
        (photos / name).write_bytes(data)
    code = main(["video", scene, "--modes", "off", "--frames", "4", "--out", str(photos)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "frame_0002.png, frame_0003.png" in err[0] and "hmblur did not write" in err[0]
    assert {p.name: p.read_bytes() for p in photos.iterdir()} == mine


def test_frames_past_the_clip_that_hmblur_did_not_write_are_kept(tmp_path):
    # Beside a longer earlier clip (4 frames, the folder's list of hmblur's files says
    # so), a shorter one removes that clip's frames 2 and 3, not a user's frame_0007.png.
    scene = slide(tmp_path)
    out = tmp_path / "frames"
    assert main(["video", scene, "--modes", "off", "--frames", "4", "--out", str(out)]) == 0
    (out / "frame_0007.png").write_bytes(b"mine")
    (out / "notes.txt").write_bytes(b"mine too")
    assert main(["video", scene, "--modes", "off", "--frames", "2", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        ".hmblur-outputs.json", "frame_0000.png", "frame_0001.png", "frame_0007.png",
        "notes.txt", "video.json"]
    assert (out / "frame_0007.png").read_bytes() == b"mine"
    assert json.loads((out / "video.json").read_text())["frames"] == 2
    # A file of hmblur's that the user changed since is the user's.
    (out / "video.json").write_text('{"frames": 9}')
    assert main(["video", scene, "--modes", "off", "--frames", "1", "--out", str(out)]) == 2
    assert (out / "video.json").read_text() == '{"frames": 9}'


# --- the camera's own motion bends screen paths ------------------------------------------

W, H, FOV, DIST, SHUTTER = 200, 100, 40.0, 5.0, 0.1
F = (H / 2) / math.tan(math.radians(FOV / 2))


def card(camera_extra: str, obj_extra: str) -> str:
    return f"""
        [camera]
        position = [0.0, 0.0, {DIST}]
        look_at = [0.0, 0.0, 0.0]
        fov_y = {FOV}
        shutter = {SHUTTER}
        {camera_extra}
        [[objects]]
        mesh = {{ box = [1.0, 1.0, 0.0001] }}
        {obj_extra}
    """


@pytest.mark.parametrize("w", [6.0, -4.0])
def test_a_rolling_camera_bends_a_still_card_as_the_card_spinning_would(tmp_path, w):
    # A camera rolling about its view axis sees the still card turn the other way: the
    # corners' screen paths are arcs with the spinning card's sagitta, r (1 - cos(theta/2)).
    rolling = scene_from(tmp_path, card(f"angular_velocity = [0.0, 0.0, {w}]", ""), "roll")
    spinning = scene_from(tmp_path, card("", f"angular_velocity = [0.0, 0.0, {-w}]"), "spin")
    r = F * math.sqrt(0.5) / (DIST - 0.00005)
    expected = r * (1 - math.cos(abs(w) * SHUTTER / 2))
    got = screen_bend(rolling, Camera(rolling.camera, W, H), 0.0, SHUTTER)
    assert got == pytest.approx(expected, rel=1e-6)
    assert got == pytest.approx(screen_bend(spinning, Camera(spinning.camera, W, H), 0.0,
                                            SHUTTER), rel=1e-9)
    assert FRACTIONS[len(FRACTIONS) // 2] == 0.5       # (the sagitta is sampled)


def test_a_camera_sliding_past_a_still_card_does_not_bend(tmp_path):
    sc = scene_from(tmp_path, card("velocity = [3.0, 1.0, 0.0]", ""))
    assert screen_bend(sc, Camera(sc.camera, W, H), 0.0, SHUTTER) < 1e-9
