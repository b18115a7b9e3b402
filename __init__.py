"""Penumbra: a real-time GLSL render engine with shadow maps and a post-process stack."""

from . import operators, properties, ui
from .engine import render_engine

modules = (properties, render_engine, operators, ui)


def register():
    for m in modules:
        m.register()


def unregister():
    for m in reversed(modules):
        m.unregister()
