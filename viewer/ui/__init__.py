"""The viewer's window-side pieces (GLFW, imgui): window, panel, overlay, input routing,
camera controls, scripts, screenshots. The render core (viewer/render) never imports these."""
