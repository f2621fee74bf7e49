"""`hmblur scene ASSET.glb`: the scene file that a bare glTF asset stands for (what `shot`,
`view`, `compare`, `bench` and `video` render when given the asset), as TOML to edit."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from world.errors import UserError
from world.loader import load_asset
from world.toml_out import dumps
from viewer.cli.args import check_output_file
from viewer.io.imageio import OutputSet

HEADER = """\
Written by `hmblur scene {asset}`:
the scene this asset stands for in shot, view, compare, bench and video (docs/scene-format.md,
"A glTF file as a scene"): the asset as one gltf entry, a camera framing it over its
animation, two lights, a 1/60 s shutter, the middle of its animation as the frame time.
Edit freely: the file loads as it is."""


def register(sub):
    p = sub.add_parser("scene", help="write the scene a bare .gltf/.glb stands for, as TOML",
                       description="Write the scene that a bare glTF asset (.gltf or .glb) "
                       "stands for when given to shot, view, compare, bench or video: the "
                       "asset with its animations, a camera framing it, lights and the frame "
                       "time, as a scene file (TOML) to edit. The asset's path in it is "
                       "relative to the output file's folder (--out), else to the current "
                       "folder (for a file saved there).")
    p.add_argument("asset", metavar="ASSET", help="a .gltf or .glb file")
    p.add_argument("--out", default=None, metavar="PATH.toml",
                   help="write the scene file here (missing folders are made) instead of "
                        "to stdout")
    p.set_defaults(run=run)


def scene_text(asset: str, out: Path | None) -> str:
    """The TOML of the scene `asset` stands for; its `gltf` path relative to `out`'s folder,
    or to the current folder without `out`."""
    path = Path(asset)
    if path.suffix.lower() not in (".gltf", ".glb"):
        raise UserError(f"scene {asset}: expected a .gltf or .glb file")
    if not path.is_file():
        raise UserError(f"scene {asset}: file not found")
    _, doc = load_asset(path)
    base = (out.parent if out is not None else Path(".")).absolute()
    doc["objects"][0]["gltf"] = Path(os.path.relpath(path.absolute(), base)).as_posix()
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
