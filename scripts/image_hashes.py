"""Every mode's image on every built-in and conformance scene, as SHA-256 of the 8-bit PNG
codes: the check that a refactor changed no pixel.

    python scripts/image_hashes.py --out hashes.json            # write the current hashes
    python scripts/image_hashes.py --check hashes.json          # exit 1 on any difference

Scenes render at 320x180 (their own time), the reference with 16 samples, two frames of
each mode in one renderer (the second frame shows state kept across frames); a scene
file that the loader cannot read is skipped with a note (an older checkout).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from world.errors import UserError  # noqa: E402
from viewer.glcontext import create_headless  # noqa: E402
from viewer.io.imageio import linear_to_srgb8  # noqa: E402
from viewer.render.graph.params import ParamSet  # noqa: E402
from viewer.render.modes import MODES  # noqa: E402
from viewer.render.renderer import Renderer  # noqa: E402
from world.loader import load_scene  # noqa: E402


def scene_files() -> list[Path]:
    builtin = sorted(p for p in (ROOT / "scenes").glob("*.toml"))
    conformance = sorted((ROOT / "tests" / "conformance").glob("*.toml"))
    return builtin + conformance


def hashes(size=(320, 180), samples=16, modes=None) -> dict[str, str]:
    ctx = create_headless()
    out = {}
    for path in scene_files():
        try:
            scene = load_scene(path)
        except UserError as exc:
            print(f"skipped {path.name}: {exc}", file=sys.stderr)
            continue
        r = Renderer(ctx, scene, size)
        try:
            for mode in modes or MODES:
                params = ParamSet()
                if "reference" in params.groups and mode == "reference":
                    params.set("reference.samples", samples)
                for k in range(2):
                    res = r.render(mode, scene.render.time + k / 60.0, params, seed=k)
                    codes = linear_to_srgb8(res.image)
                    out[f"{path.stem}/{mode}/{k}"] = hashlib.sha256(codes.tobytes()).hexdigest()
        finally:
            r.release()
        print(f"{path.stem}: done", file=sys.stderr)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--out", help="write the hashes to this JSON file")
    g.add_argument("--check", help="compare with the hashes in this JSON file")
    ap.add_argument("--modes", default=None, help="comma-separated modes (default: all)")
    args = ap.parse_args()
    got = hashes(modes=args.modes.split(",") if args.modes else None)
    if args.out:
        Path(args.out).write_text(json.dumps(got, indent=1, sort_keys=True) + "\n")
        print(f"{args.out}: {len(got)} images")
        return 0
    want = json.loads(Path(args.check).read_text())
    diff = sorted(k for k in want.keys() & got.keys() if want[k] != got[k])
    for k in diff:
        print(f"differs: {k}")
    print(f"{len(want.keys() & got.keys())} compared, {len(diff)} differ, "
          f"{len(want.keys() - got.keys())} missing, {len(got.keys() - want.keys())} new")
    return 1 if diff else 0


if __name__ == "__main__":
    sys.exit(main())
