"""Penumbra: a real-time GLSL render engine with shadow maps and a post-process stack."""

# Blender imports this file as the add-on's package. A test runner may also import it as a
# plain module (pytest sets up the checkout's folder as a package, and a folder name that is
# no Python name, such as "fresh-ci", cannot be one): then it has nothing to register.
if __package__:
    from . import operators, properties, ui
    from .engine import render_engine

    modules = (properties, render_engine, operators, ui)
else:
    modules = ()


def register():
    for m in modules:
        m.register()


def unregister():
    for m in reversed(modules):
        m.unregister()
