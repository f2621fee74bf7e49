"""Every mode on every built-in scene against the reference, per region: FLIP bounds set
just above what the modes measure, so a quality regression turns the suite red.

160x90, the reference with 16 sub-frames (its per-sub-frame visibility classifies the
regions: viewer/render/modes/regions.py), every frame at the scene's own time. The modes are MODES'
(the reference aside): a new mode joins by itself, held to the worst bound of the
post-process modes (mcguire, ue4) until it has its own. Rerun the measurement with
`python tests/test_quality_matrix.py` (prints the table below with measured values).
"""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from viewer.eval.metrics import image_metrics  # noqa: E402
from viewer.render.graph.params import ParamSet  # noqa: E402
from viewer.render.modes import MODES  # noqa: E402
from viewer.render.renderer import Renderer  # noqa: E402
from viewer.render.modes.reference import REGIONS as REGION_MAP  # noqa: E402
from world.loader import builtin_scene_names, builtin_scene_path, load_scene  # noqa: E402

SIZE, SAMPLES = (160, 90), 16
REGIONS = ("all", "static", "inner", "outer")
POST = ("mcguire", "ue4")
MARGIN = (1.1, 0.002)          # bound = measured * 1.1 + 0.002 (a GPU driver rasterises a
                               # little differently; a regression moves FLIP by far more)

# Measured FLIP (mean over the region; all, static, inner, outer); bounds: MARGIN applied.
MEASURED = {
    "fan": {"off": (0.0413, 0.0104, 0.3878, 0.2522),
        "mcguire": (0.0391, 0.0124, 0.3656, 0.2085),
        "ue4": (0.0336, 0.0106, 0.2882, 0.1925),
        "guertin": (0.0375, 0.0128, 0.3492, 0.1898),
        "hybrid": (0.0154, 0.0056, 0.1241, 0.0838)},
    "living_room": {"off": (0.0092, 0.0013, 0.2463, 0.1982),
        "mcguire": (0.0060, 0.0008, 0.2120, 0.0996),
        "ue4": (0.0046, 0.0007, 0.0966, 0.1183),
        "guertin": (0.0058, 0.0008, 0.2071, 0.0880),
        "hybrid": (0.0021, 0.0004, 0.0484, 0.0473)},
    "pan": {"off": (0.1765, 0.1549, 0.2415, 0.2331),
        "mcguire": (0.0750, 0.0679, 0.0951, 0.0951),
        "ue4": (0.0865, 0.0818, 0.1002, 0.0991),
        "guertin": (0.0714, 0.0645, 0.0914, 0.0905),
        "hybrid": (0.0699, 0.0648, 0.0832, 0.0853)},
    "rover": {"off": (0.0162, 0.0107, 0.1989, 0.1396),
        "mcguire": (0.0134, 0.0086, 0.1739, 0.1236),
        "ue4": (0.0128, 0.0085, 0.1472, 0.1181),
        "guertin": (0.0149, 0.0100, 0.1868, 0.1198),
        "hybrid": (0.0125, 0.0086, 0.1304, 0.1107)},
    "spinner": {"off": (0.0650, 0.0190, 0.3369, 0.2730),
        "mcguire": (0.0543, 0.0156, 0.3499, 0.1788),
        "ue4": (0.0460, 0.0134, 0.2532, 0.1829),
        "guertin": (0.0536, 0.0159, 0.3496, 0.1679),
        "hybrid": (0.0218, 0.0101, 0.0712, 0.0906)},
    "thin": {"off": (0.0411, 0.0076, 0.4251, 0.1658),
        "mcguire": (0.0498, 0.0073, 0.3187, 0.2340),
        "ue4": (0.0274, 0.0066, 0.2005, 0.1128),
        "guertin": (0.0400, 0.0056, 0.2837, 0.1862),
        "hybrid": (0.0198, 0.0056, 0.0962, 0.0834)},
    "turning_car": {"off": (0.0814, 0.0051, 0.5627, 0.3442),
        "mcguire": (0.0539, 0.0063, 0.3370, 0.2402),
        "ue4": (0.0496, 0.0060, 0.2819, 0.2521),
        "guertin": (0.0532, 0.0095, 0.3240, 0.2093),
        "hybrid": (0.0138, 0.0021, 0.0822, 0.0603)},
    "wheel": {"off": (0.0182, 0.0091, 0.2862, 0.2122),
        "mcguire": (0.0167, 0.0083, 0.2735, 0.1917),
        "ue4": (0.0174, 0.0087, 0.2768, 0.2018),
        "guertin": (0.0166, 0.0084, 0.2707, 0.1838),
        "hybrid": (0.0062, 0.0032, 0.0814, 0.0781)}
}


def bound(scene: str, mode: str, region: str) -> float:
    k = REGIONS.index(region)
    known = MEASURED[scene]
    value = known[mode][k] if mode in known else max(known[m][k] for m in POST)
    return value * MARGIN[0] + MARGIN[1]


def measure(ctx, name: str) -> dict:
    """{mode: {region: FLIP or None (empty region)}} and the region pixel counts."""
    scene = load_scene(builtin_scene_path(name))
    r = Renderer(ctx, scene, SIZE)
    try:
        p = ParamSet()
        p.set("reference.samples", SAMPLES)
        ref = r.render("reference", scene.render.time, p, record_visibility=True)
        region = ref.host[REGION_MAP]
        out = {}
        for mode in MODES:
            if mode != "reference":
                m = image_metrics(r.render(mode, scene.render.time, p).image, ref.image,
                                  region)
                out[mode] = {k: m[k]["flip"] for k in REGIONS}
                pixels = {k: m[k]["pixels"] for k in REGIONS}
    finally:
        r.release()
    return out, pixels


def test_the_table_covers_every_builtin_scene():
    assert sorted(MEASURED) == builtin_scene_names()


@pytest.mark.parametrize("name", sorted(MEASURED))
def test_every_mode_within_its_flip_bounds_against_the_reference(ctx, name):
    got, pixels = measure(ctx, name)
    assert min(pixels["inner"], pixels["outer"]) > 200     # regions of some size
    over = [f"{mode} {region}: FLIP {got[mode][region]:.4f} > {bound(name, mode, region):.4f}"
            for mode in got for region in REGIONS
            if got[mode][region] > bound(name, mode, region)]
    assert not over, f"{name}: " + "; ".join(over)
    # The hybrid's reveal is what the method is for: its inner blur beats every
    # post-process mode's (with the reveal off it falls to theirs).
    for mode in POST:
        assert got["hybrid"]["inner"] < got[mode]["inner"], (name, mode)


if __name__ == "__main__":
    from viewer.glcontext import create_headless
    gl = create_headless()
    for name in builtin_scene_names():
        got, pixels = measure(gl, name)
        print(f'    "{name}": {{' + ",\n        ".join(
            f'"{m}": (' + ", ".join(f"{got[m][k]:.4f}" for k in REGIONS) + ")" for m in got)
            + "},", pixels)
