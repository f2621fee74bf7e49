"""`hmblur scene ASSET.glb`: the scene file that a bare glTF asset stands for (what `shot`,
`view`, `compare`, `bench` and `video` render when given the asset), as TOML to edit."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from world.assets import allowed_roots, within
from world.errors import UserError, printable
from world.loader import load_asset
from world.toml_out import dumps
from viewer.cli.args import check_output_file
from viewer.io.imageio import OutputSet

HEADER = """\
Written by `hmblur scene {asset}`:
the scene this asset stands for in shot, view, compare, bench and video (docs/scene-format.md,
"A glTF file as a scene"): the asset as one gltf entry, a camera framing its moving
parts over the animation from a side that sees them, two lights, a 1/60 s shutter, and
a time at which they move as the frame time.
Edit freely: the file loads as it is."""


def register(sub):
    p = sub.add_parser("scene", help="write the scene a bare .gltf/.glb stands for, as TOML",
                       description="Write the scene that a bare glTF asset (.gltf or .glb) "
                       "stands for when given to shot, view, compare, bench or video: the "
                       "asset with its animations, a camera framing it, lights and the frame "
                       "time, as a scene file (TOML) to edit. The asset's path in it is "
                       "relative to the output file's folder (--out), else to the current "
                       "folder (for a file saved there). A scene names files only in its own "
                       "folder or below it, so --out must lie in the asset's folder or a "
                       "folder above it (a built-in asset: anywhere, by its absolute path).")
    p.add_argument("asset", metavar="ASSET", help="a .gltf or .glb file")
    p.add_argument("--out", default=None, metavar="PATH.toml",
                   help="write the scene file here (missing folders are made) instead of "
                        "to stdout")
    p.set_defaults(run=run)


def asset_reference(asset: Path, scene_file: Path) -> str | None:
    """The `gltf` path that a scene file at `scene_file` loads `asset` by under the asset-file
    rule (world/assets.py): relative to the scene's folder where the asset lies in it or
    below it, absolute for a built-in asset elsewhere; None where no path would load."""
    real = Path(os.path.realpath(asset))
    folder, builtin = allowed_roots(scene_file.absolute())
    if within(real, folder):
        # the path as the user wrote it, where it resolves to the same file (links kept)
        given = os.path.relpath(asset.absolute(), scene_file.absolute().parent)
        if Path(os.path.realpath(scene_file.absolute().parent / given)) == real:
            return Path(given).as_posix()
        return real.relative_to(folder).as_posix()
    if within(real, builtin):
        return real.as_posix()
    return None


def scene_text(asset: str, out: Path | None) -> str:
    """The TOML of the scene `asset` stands for; its `gltf` path loads from `out`'s folder
    (refused where none would), or without `out` from the current folder (a note on stderr
    where none would)."""
    path = Path(asset)
    if path.suffix.lower() not in (".gltf", ".glb"):
        raise UserError(f"scene {asset}: expected a .gltf or .glb file")
    if not path.is_file():
        raise UserError(f"scene {asset}: file not found")
    where = out if out is not None else Path("scene.toml")
    ref = asset_reference(path, where)
    home = Path(os.path.realpath(path)).parent
    if ref is None and out is not None:
        raise UserError(f"scene --out {out}: a scene there could not load {asset}: a scene "
                        "names files only in its own folder or below it (docs/scene-format.md, "
                        f"\"Asset files\"); write it in {home} or a folder above it")
    _, doc = load_asset(path)
    if ref is None:
        note = (f"hmblur: note: saved in the current folder, this scene would not load {asset} "
                "(a scene names files only in its own folder or below it); save it in "
                f"{home} or a folder above it, with its gltf path edited")
        print(printable(note), file=sys.stderr)
        ref = Path(os.path.relpath(path.absolute(), Path(".").absolute())).as_posix()
    doc["objects"][0]["gltf"] = ref
    return dumps(doc, HEADER.format(asset=asset))


def run(args) -> int:
    out = None
    if args.out is not None:
        out = check_output_file(args.out, suffix=".toml")
    text = scene_text(args.asset, out)
    if out is None:
        sys.stdout.write(text)
        return 0
    files = OutputSet()
    data = text.encode("utf-8")
    files.add(out, lambda f: f.write(data))
    files.commit()
    print(f"{out}: the scene of {args.asset}", file=sys.stderr)
    return 0
