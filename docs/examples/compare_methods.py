"""Your method beside ours, as a notebook would run it (docs/api.md): three built-in modes
and a user blur pass rendered on one scene, each scored per blur region against the
reference, and the table printed.

    python docs/examples/compare_methods.py [SCENE] [WxH]     (default: living_room 160x90)
"""
import sys
from pathlib import Path

import pandas as pd

import hybrid_mblur as hm

HERE = Path(__file__).resolve().parent


def main(scene_name: str = "living_room", size: tuple[int, int] = (160, 90),
         samples: int = 16) -> pd.DataFrame:
    scene = hm.load_scene(scene_name)
    rows = []
    with hm.Renderer(size=size) as r:
        # A user pass runs like a mode once it is registered under a name.
        r.register("naive_numpy", hm.py_pass(HERE / "numpy_gather.py", "gather"))
        ref = r.reference(scene, samples=samples)        # the ground truth and its regions
        for mode in ("mcguire", "ue4", "hybrid", "naive_numpy"):
            image = r.render(scene, mode)                # image: linear float32 (H, W, 3)
            table = hm.scores(image, ref)                # PSNR, SSIM, FLIP per region
            rows.append(table.reset_index().assign(method=mode))
    out = pd.concat(rows, ignore_index=True)[["method", "region", "pixels", "psnr", "ssim",
                                               "flip"]]
    print(f"{scene.name} {size[0]}x{size[1]}, reference of {samples} sub-frames, "
          f"{ref.masks()['inner'].sum()} inner-blur pixels")
    print(out.to_string(index=False, float_format=lambda x: f"{x:.4f}"))
    return out


if __name__ == "__main__":
    name = sys.argv[1] if len(sys.argv) > 1 else "living_room"
    wh = tuple(int(x) for x in sys.argv[2].split("x")) if len(sys.argv) > 2 else (160, 90)
    main(name, wh)
