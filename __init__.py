"""Penumbra: a real-time GLSL render engine with shadow maps and a post-process stack."""

from . import properties
from .engine import render_engine
from . import operators, ui

modules = (properties, render_engine, operators, ui)


def register():
    for m in modules:
        m.register()


def unregister():
    for m in reversed(modules):
        m.unregister()
