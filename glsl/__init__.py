"""GLSL sources of hybrid-mblur, shipped as package data (see viewer.render.graph.shaders)."""
from pathlib import Path

DIR = Path(__file__).resolve().parent
