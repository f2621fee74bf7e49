"""hybrid_mblur: the Python face of hybrid-mblur (docs/api.md).

    import hybrid_mblur as hm

    scene = hm.load_scene("living_room")
    with hm.Renderer(size=(320, 180)) as r:
        r.register("mine", hm.py_pass("docs/examples/numpy_gather.py", "gather"))
        ref = r.reference(scene)
        for mode in ("mcguire", "hybrid", "mine"):
            print(mode, hm.scores(r.render(scene, mode), ref))
    table = hm.compare(scene, ["mcguire", ("mine", "glsl:docs/examples/naive_gather.frag")])

Scenes (scenes.py), the renderer that owns its GL context (renderer.py), results as arrays
(results.py), user blur passes (methods.py), scores per region (scores.py), compare and
sweep as DataFrames (tables.py). `hmblur` runs on the same code: its shot and compare
render through Renderer."""
from __future__ import annotations

from world.errors import UserError
from viewer.render.modes.user import MethodError
from .methods import BlurInputs, UserPass, glsl_pass, py_pass
from .renderer import Renderer, param_set
from .results import Reference, Render
from .scenes import Scene, builtin_scenes, load_scene
from .scores import SPACE, scores
from .tables import compare, comparison_table, sweep, variants_of

__all__ = ["BlurInputs", "MethodError", "Reference", "Render", "Renderer", "SPACE", "Scene",
           "UserError", "UserPass", "builtin_scenes", "compare", "comparison_table",
           "glsl_pass", "load_scene", "param_set", "py_pass", "scores", "sweep",
           "variants_of"]
