"""hybrid-mblur: a deferred ModernGL renderer with McGuire 2012, UE4-style and hybrid
(ray-revealed) motion blur, and a ground-truth reference to measure them against.

The render core (everything but `viewer.ui.app`) never imports glfw or imgui_bundle: the
caller hands it a moderngl.Context.
"""
