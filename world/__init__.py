"""The scene model below both renderers: scene files and their loader, the camera, the
transforms and the conventions that the rasteriser (viewer/render), the ray tracer
(raytrace) and the tests share. Imports nothing from either renderer."""
