"""What each buffer of a `--buffers` dump holds: one table, from which the dump's
README.txt is written (with each file's dtype, shape and the value range it holds).

Arrays are in image orientation (top row first). Vectors are in pixels, GL axes (x right,
y up). "D" is the full screen-space displacement over the exposure,
p(t + shutter/2) - p(t - shutter/2). Depths are linear view depths in metres (the
background's depth is a large constant). Ids: object k of the scene file is id k, 0 the
background.
"""
from __future__ import annotations

import numpy as np

# name: what it holds, channel by channel where it has several
BUFFERS = {
    "color": "linear RGB colour of the sharp frame at time t (A = 1)",
    "depth": "linear view depth, m",
    "normal": "world-space normal xyz (A unused), half floats",
    "id": "object id seen at the pixel (0 = background)",
    "velocity": "displacement D over the exposure, px (x, y)",
    "hybrid_front": "the hybrid's packed front layer: D.x, D.y (px), depth (m), object id",
    "hybrid_path": "the pixel's screen path over the exposure (hybrid.segments = K): the "
                   "offsets (px) from its position at t of its positions at t_k = t - s/2 "
                   "+ k s/K: K = 2: x, y at k = 0, then at k = 2; K = 4: k = 0, then k = 1",
    "hybrid_path2": "K = 4: the path's offsets at k = 3, then at k = 4 (px)",
    "mcguire_velocity": "McGuire 2012 velocity: half of D clamped to the blur limit, px",
    "mcguire_tilemax_x": "TileMax first step (k x 1 per row): largest half-velocity, px",
    "mcguire_tilemax": "TileMax: the largest half-velocity per k x k tile, px",
    "mcguire_neighbormax": "NeighborMax: the largest TileMax over the 3x3 tiles around, px",
    "mcguire": "McGuire 2012 output, linear RGB (A = 1)",
    "guertin_velocity": "Guertin 2014 velocity: half of D clamped to [0.5 px, the blur "
                        "limit], px",
    "guertin_tilemax_x": "TileMax first step (k x 1 per row): largest half-velocity, px",
    "guertin_tilemax": "TileMax: the largest half-velocity per k x k tile, px",
    "guertin_neighbormax": "NeighborMax over the 3x3 tiles around, a diagonal tile only "
                           "where its vector points toward the centre tile, px",
    "guertin": "Guertin 2014 output, linear RGB (A = 1)",
    "ue4_flat": "UE4-style flattened velocity: v.x, v.y (half of D clamped, px), depth (m), |v| (px)",
    "ue4_tiles": "per tile: min velocity x, y and max velocity x, y (by length), px",
    "ue4_dilated": "ue4_tiles after the swept-quad dilation: min x, y and max x, y, px",
    "ue4": "UE4-style output, linear RGB (A = 1)",
    "motion_tiles_x": "motion tiles, first step (per row of 16 px): longest |D| (px; with a "
                      "path its extent, twice the farthest offset), the run's object id or "
                      "-1 where it holds an id boundary",
    "motion_tiles": "per 16 x 16 tile: longest |D| (px; with a path its extent), 1 where "
                    "the tile may hold an id boundary, else 0",
    "hybrid_tilemax_x": "hybrid TileMax first step (k x 1 per row): largest D, px (with a "
                        "path: the chord of the longest path)",
    "hybrid_tilemax": "hybrid TileMax: the largest D per k x k tile, px (as above)",
    "hybrid_neighbormax": "hybrid NeighborMax: the largest TileMax over the 3x3 tiles, px",
    "hybrid_tilemax_x_path": "with a path: the path (as hybrid_path) of hybrid_tilemax_x's "
                             "texel of longest path extent",
    "hybrid_tilemax_x_path2": "K = 4: the rest of that path (as hybrid_path2)",
    "hybrid_tilemax_path": "with a path: the path of hybrid_tilemax's texel (longest extent)",
    "hybrid_tilemax_path2": "K = 4: the rest of that path (as hybrid_path2)",
    "hybrid_neighbormax_path": "with a path: the path of hybrid_neighbormax's tile (longest "
                               "extent over the 3x3 tiles)",
    "hybrid_neighbormax_path2": "K = 4: the rest of that path (as hybrid_path2)",
    "mask_displacement": "ray mask step 1 (range check on): 1 where the displaced position "
                         "lands on a different, farther object, else 0",
    "mask_relative": "ray mask step 1: displacement relative to the background seen there, "
                     "px (read only at survivors)",
    "mask_edge": "ray mask step 2 (range check on): 1 on survivors with a Sobel edge of log "
                 "depth or normal, else 0",
    "mask_edge_probe": "at edge pixels: half |relative D| (px) and the object id, else 0",
    "mask_survivors_x": "per row of 16 px: 1 where step 1 has a survivor",
    "mask_survivors": "per 16 x 16 tile: 1 where step 1 has a survivor",
    "ray_mask": "the pixels that get a ray: the pixel's own object id where masked, 0 elsewhere",
    "mask_edge_ids_x": "per row of 16 px: bits of the objects with an edge there (2 words)",
    "mask_edge_ids": "per 16 x 16 tile: bits of the objects with an edge in it (2 words)",
    "mask_edge_near": "per tile: object bits with an edge within a tile of it, and the "
                      "largest reach of those edges",
    "mask_edge_reach_x": "mask_edge_reach, first step (per row of tiles)",
    "mask_edge_reach": "per tile: bits of the objects whose edges reach it",
    "hybrid_back": "revealed layer: D.x, D.y (px), depth (m), 1 + object id (0 = nothing "
                   "revealed)",
    "hybrid_back_color": "revealed layer's linear RGB colour, A = 1 where revealed",
    "ray_mask_tiles": "per tile: ray-mask coverage read by the time composite",
    "hybrid": "hybrid output, linear RGB (A = 1)",
    "reference": "reference output: the mean of the sub-frames, linear RGB (A = 1)",
}
# The post-process modes' tile paths (GROUP.segments > 1): the winner's path beside its vector.
for _tiles in ("mcguire_tilemax_x", "mcguire_tilemax", "mcguire_neighbormax",
               "guertin_tilemax_x", "guertin_tilemax", "guertin_neighbormax",
               "ue4_tiles", "ue4_dilated"):
    BUFFERS[_tiles + "_path"] = (f"with a path: the path (as hybrid_path) of the texel or "
                                 f"tile whose vector {_tiles} holds (longest extent)")
    BUFFERS[_tiles + "_path2"] = "K = 4: the rest of that path (as hybrid_path2)"
# Prefixes: the same buffer for another set of targets.
PREFIXES = {
    "sub_": "the reference's last sub-frame G-buffer: ",
    "static_": "the raster of the static objects alone (kept per view): ",
}


def describe(name: str) -> str:
    """What buffer `name` holds ("" when the table does not know it)."""
    if name in BUFFERS:
        return BUFFERS[name]
    for prefix, text in PREFIXES.items():
        if name.startswith(prefix) and name[len(prefix):] in BUFFERS:
            return text + BUFFERS[name[len(prefix):]]
    return ""


def _range(a: np.ndarray) -> str:
    if a.size == 0:
        return "empty"
    if a.ndim == 3:
        parts = [_range(a[..., c]) for c in range(a.shape[2])]
        return "; ".join(f"ch{c} {p}" for c, p in enumerate(parts))
    lo, hi = a.min(), a.max()
    if np.issubdtype(a.dtype, np.integer):
        return f"{int(lo)}..{int(hi)}"
    return f"{float(lo):.4g}..{float(hi):.4g}"


def buffers_readme(buffers: dict[str, np.ndarray], mode: str) -> str:
    """The README.txt of a `--buffers` folder: each buffer's files, dtype, shape
    (rows, columns, channels), what it holds and the range of values in this dump."""
    lines = [f"Buffers of one '{mode}' frame (hmblur shot --buffers).", "",
             "NAME.npy holds the raw texture (numpy.load), NAME.png a viewable picture of it",
             "(colour: sRGB; depth: log grey, near bright; ids: a colour per id; vectors:",
             "hue = direction, brightness = length). Arrays are top row first; vectors are in",
             "pixels with GL axes (x right, y up); D is the displacement over the exposure;",
             "depths are linear view depths in metres; object k of the scene file is id k.",
             "Tiled buffers hold one texel per tile.", ""]
    for name, a in buffers.items():
        a = np.asarray(a)
        shape = "x".join(map(str, a.shape))
        lines.append(f"{name}.npy  {a.dtype}  {shape}")
        lines.append(f"    {describe(name) or '(not described)'}")
        lines.append(f"    values here: {_range(a)}")
    return "\n".join(lines) + "\n"
