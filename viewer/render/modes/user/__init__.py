"""User blur passes: a researcher's own method run beside the built-in modes.

Two kinds, named wherever a mode is (`--variant NAME=glsl:PATH`, `--variant
NAME=py:PATH:FUNCTION`, a sweep file's `mode`, the Python API): a GLSL fragment shader
drawn as a full-screen pass, or a Python function on numpy arrays run as a host pass. Both
read the same inputs (inputs.py: the G-buffer and the tile reductions of its motion) and
write the blurred linear colour; their pipeline (pipeline.py) is the G-buffer, TileMax,
NeighborMax and the user's pass, so `hmblur bench` times the pass and `hmblur graph` shows
it. A method file is code that runs: method.py reads it once, as bytes, so that the bytes
run (here or on a sweep's worker) are the bytes its digest names (docs/api.md)."""
from .inputs import BlurInputs, INPUT_TEXTURES, OUTPUT, SAMPLERS, USER_GROUPS
from .method import MethodError, UserPass, parse_method
from .pipeline import user_pipeline

__all__ = ["BlurInputs", "INPUT_TEXTURES", "OUTPUT", "SAMPLERS", "USER_GROUPS",
           "MethodError", "UserPass", "parse_method", "user_pipeline"]
