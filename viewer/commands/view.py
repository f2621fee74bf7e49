"""`hmblur view`: the interactive viewer (a GLFW window with an imgui panel), also runnable
for a fixed number of frames with a script, for tests and screenshots."""
from __future__ import annotations

import argparse
import textwrap
from pathlib import Path

from world import limits
from viewer.cli import args as cliargs
from viewer.render.modes import MODES
from viewer.io.video_writer import OUT_HELP, video_paths

KEYS = """\
keys and mouse (over the scene, not the panel):
  left drag      orbit (with fly look: turn the view)
  right/middle   pan
  wheel          zoom
  W A S D Q E    fly forward, left, back, right, down, up
  space          play / pause the animation
  R              reset the view        F  fly look on/off
  H              hide / show the panel (its title bar's arrow collapses it)
  O              overlay: full, compact (default in windows under 600 px tall), off
  P or F12       screenshot: PNG + sidecar in --shot-dir
  V              record: start / stop a recording into --shot-dir
  Esc            quit"""


def register(sub):
    from viewer.ui.script import format_help
    intro, _, rows = format_help().partition("\n")
    script_help = textwrap.fill(intro, 88) + "\n" + rows
    p = sub.add_parser("view", help="interactive viewer window",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="The interactive viewer (GLFW + imgui): a panel for the "
                       "mode, its parameters, the buffer shown, the animation and the camera; "
                       "an overlay with frame and pass times and the mode's counters. With "
                       "--frames it runs that many frames and exits (scripts, screenshots, "
                       "tests; under Xvfb without a display).",
                       epilog=KEYS + "\n\n" + script_help)
    cliargs.add_scene_args(p)
    cliargs.add_mode_arg(p, MODES)
    p.add_argument("--frames", type=str, default=None, metavar="N",
                   help="run this many frames, then exit (no person needed)")
    p.add_argument("--screenshot", default=None, metavar="PNG",
                   help="with --frames: save the window (panel and overlay included) at the end")
    p.add_argument("--script", default=None, metavar="FILE",
                   help="scripted UI actions by frame number (text or JSON; the format is "
                        "below)")
    p.add_argument("--stats-json", default=None, metavar="FILE",
                   help="write fps, per-pass ms, memory (RSS) samples and errors at exit")
    p.add_argument("--record", default=None, metavar="PATH",
                   help="record the shown image from the first frame to the end (key V starts "
                        "and stops a recording into --shot-dir): " + OUT_HELP)
    p.add_argument("--record-fps", default=None, metavar="F",
                   help="frames per second of recordings; while recording, a playing "
                        "animation advances 1/F per frame (default 30)")
    p.add_argument("--shot-dir", default=".", metavar="DIR",
                   help="folder for screenshots taken with F12 / P (default: current folder)")
    p.set_defaults(run=run)


def run(args) -> int:
    s = cliargs.setup(args)
    args.mode = cliargs.pick_mode(args.mode, s.sidecar, MODES)
    frames = (cliargs.parse_int("--frames", args.frames, 1, limits.MAX_FRAMES)
              if args.frames is not None else None)
    if args.screenshot is not None and frames is None:
        raise cliargs.UserError("--screenshot needs --frames N (the window is saved at frame N)")
    screenshot = (cliargs.check_output_file(args.screenshot, "--screenshot", suffix=".png")
                  if args.screenshot is not None else None)
    stats = cliargs.check_output_file(args.stats_json, "--stats-json") if args.stats_json is not None else None
    shot_dir = cliargs.check_output_dir(args.shot_dir, "--shot-dir", create=False)
    if args.record is not None:
        video_paths(args.record, "--record")
    fps = 30.0 if args.record_fps is None else cliargs.parse_fps("--record-fps", args.record_fps)
    from viewer.ui.script import load_script
    script = load_script(args.script) if args.script else []
    # Imported here so that `hmblur shot` and `--help` never load glfw or imgui.
    from viewer.ui.app import App, RunOptions
    app = App(s, args.scene, args.mode, RunOptions(frames, screenshot, stats, Path(shot_dir), script,
                                                      args.record, fps))
    try:
        return app.run()
    finally:
        app.release()
