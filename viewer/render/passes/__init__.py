"""Passes shared by several modes: the G-buffer (and its kept static raster), motion tiles,
the tiled gather draw, depth and velocity encodings, the debug view."""
