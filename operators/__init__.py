from . import compare, layers, presets

modules = (layers, presets, compare)


def register():
    for m in modules:
        m.register()


def unregister():
    for m in reversed(modules):
        m.unregister()
