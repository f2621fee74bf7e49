"""The render core: takes a moderngl.Context from its caller; never imports glfw or imgui."""
