"""What the program can hold: every count, size and rate a user can give (flags, scene
keys, sidecar keys, asset files) is checked against these before work starts, and a value
past one is a one-line error naming it (docs/scene-format.md, "Limits")."""
import os

# Scene numbers: the shaders compute in float32 (7 significant digits, at most 3.4e38), a
# position or velocity past 1e7 loses every centimetre and products of two overflow.
MAX_SCENE_NUMBER = 1e7
# Frame times, seconds (flags, [render] time, key times, sidecars): past it the float32
# transforms of p + v t lose every digit of a frame's motion.
MAX_TIME = 1e6
# Image sides and pixels (flags, [render], sidecars): a hybrid frame of 4.2 Mpx (2560x1600
# fits) peaks at ~1.2 GB on llvmpipe, a 3840x2160 one at 2.4 GB.
MAX_FRAME_SIZE = 16384
MAX_FRAME_PIXELS = 2048 * 2048
# Triangles of a scene, all meshes together (a revolve or file counted before it is built
# or read into the renderer): ~0.5 kB each through trimesh, Embree and the GPU.
MAX_TRIANGLES = 2_000_000
# Objects and lights of a scene (a glTF entry's mesh nodes are objects): each object costs
# ~25 kB of host memory and a draw call per pass; every pixel's shading loops over the
# lights.
MAX_OBJECTS = 10_000
MAX_LIGHTS = 4_096
# Names (of objects, scenes, glTF nodes and animations): they head error messages and
# name parents.
MAX_NAME_CHARS = 1024
# Asset files a scene names (meshes, images) and their decoded size.
MAX_SCENE_BYTES = 16 << 20
MAX_MESH_BYTES = 256 << 20
MAX_IMAGE_BYTES = 256 << 20
MAX_IMAGE_PIXELS = 4096 * 4096          # a texture: 16.8 Mpx, 200 MB as float32 RGB
# Texels a scene's images hold together (scene-file textures and glTF images alike, each
# distinct image once, a glTF image tinted by a material's colour once more): each is
# 12 bytes decoded and as much again on the GPU.
MAX_SCENE_IMAGE_PIXELS = 2 * 4096 * 4096
# glTF assets (world/gltf/), each bounded before it is allocated so that a small hostile
# file cannot make the program allocate gigabytes.
MAX_GLTF_FILE_BYTES = 256 << 20         # any one .gltf/.glb/.bin/image file or data URI
MAX_GLTF_COMPONENTS = 2 ** 26           # decoded accessor components together (512 MiB as float64)
# Vertices of an asset's mesh nodes, each node's mesh counted (as triangles are against
# MAX_TRIANGLES): three per triangle drawn.
MAX_GLTF_VERTICES = 3 * MAX_TRIANGLES
MAX_GLTF_NODES = 2 ** 16
MAX_GLTF_JOINTS = 2 ** 16               # per skin
MAX_GLTF_ITEMS = 2 ** 16                # entries of any array (meshes, accessors, ...)
MAX_GLTF_JSON_DEPTH = 64
# `--params FILE.json`: a sidecar is a few kB; JSON nesting and integers beyond these are
# not a sidecar's.
MAX_PARAMS_BYTES = 4 << 20
# A user's blur pass (a GLSL or Python file, viewer/render/modes/user/): one source file.
MAX_METHOD_BYTES = 1 << 20
# Frames of a video, a bench or a viewer run, and a video's rate.
MAX_FRAMES = 100_000
MIN_FPS, MAX_FPS = 1e-3, 1e3
# Seeds: the jitter keys use the low 32 bits.
MAX_SEED = 2 ** 32 - 1
# Exposure times (`camera.shutter`, `compare --shutter`, a sweep's `shutters`): a scene
# number, like any other the scene file gives.
MAX_SHUTTER = MAX_SCENE_NUMBER
# Variants of one comparison (`compare --modes/--variant`, a sweep's variants after grid
# expansion), and the pixels of the images it holds at once (each variant's and the
# reference's, kept for the metrics and the strip): 6 frames of the largest size.
MAX_VARIANTS = 32
MAX_COMPARE_PIXELS = 6 * MAX_FRAME_PIXELS
# A sweep: cells (scenes x times x shutters x sizes x samples x seeds), renders (cells x
# variants: the table holds 4 rows each), scenes a glob may bring, directory entries a
# glob may visit (it never follows a symlinked folder), the bytes of every scene and
# asset file its workers receive, a cell file it reads back, and the sweep file.
MAX_SWEEP_CELLS = 10_000
MAX_SWEEP_RENDERS = 50_000
MAX_SWEEP_SCENES = 1_000
MAX_GLOB_ENTRIES = 100_000
MAX_SWEEP_BYTES = 512 << 20
MAX_CELL_FILE_BYTES = 16 << 20
MAX_SWEEP_FILE_BYTES = 1 << 20
# The list of the files hmblur wrote in an output folder (viewer/io/outdir.py): a video's
# 100000 frames take ~6 MB.
MAX_OUTPUTS_MANIFEST_BYTES = 32 << 20
# Local sweep workers: a worker renders on every core (llvmpipe's threads, the ray
# kernels), so more workers than cores only add memory (~600 MB each).
MAX_LOCAL_WORKERS = os.cpu_count() or 1
