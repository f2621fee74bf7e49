"""GLSL sources of hybrid-mblur, shipped as package data (see viewer.shaders)."""
from pathlib import Path

DIR = Path(__file__).resolve().parent
