"""Writes the shipped post-stack looks to presets/post_stack/ with the same writer users'
presets go through (operators/presets.py), so shipped and saved presets share one format.

    .venv/blender-5.2/bin/python -m tools.make_presets
"""

from devkit import scenes, session

# name -> [(effect, layer name, mix, {param: value})], top of the stack first.
LOOKS = {
    "CRT": [
        ("FISHEYE", "Tube bulge", 1.0, {"strength": 0.25, "edge": "BLACK"}),
        ("BLUR", "Phosphor", 0.35, {"radius": 1}),
        ("SCANLINES", "Scanlines", 1.0, {"count": 220, "thickness": 0.45, "intensity": 0.6, "scroll_speed": 0.05}),
        ("NOISE", "Signal noise", 1.0, {"amount": 0.04, "size": 1, "monochrome": True}),
        ("VIGNETTE", "Tube edge", 1.0, {"radius": 0.9, "softness": 0.5, "roundness": 0.6}),
    ],
    "Old_Film": [
        ("SEPIA", "Sepia", 1.0, {"amount": 0.85}),
        ("NOISE", "Grain", 1.0, {"amount": 0.08, "size": 2, "monochrome": True}),
        ("SCANLINES", "Gate flicker", 0.5, {"count": 3, "thickness": 0.1, "intensity": 0.15, "scroll_speed": 0.37}),
        ("VIGNETTE", "Burn", 1.0, {"radius": 0.6, "softness": 0.9, "roundness": 1.0}),
    ],
    "Soft_Glow": [
        ("GLOW", "Glow", 1.0, {"threshold": 0.6, "knee": 0.5, "intensity": 0.8, "radius": 12}),
        ("BLUR", "Diffusion", 0.2, {"radius": 4}),
        ("VIGNETTE", "Vignette", 0.6, {"radius": 1.0, "softness": 0.8}),
    ],
    "Vintage_Lens": [
        ("LENS_FLARE", "Flare", 1.0, {"threshold": 0.8, "intensity": 0.6, "mode": "SCREEN", "ghosts": 5}),
        ("COLORIZER", "Warm grade", 0.5, {"blur_radius": 2, "strength": 0.6}),
        ("FISHEYE", "Barrel", 1.0, {"strength": 0.12}),
        ("VIGNETTE", "Vignette", 1.0, {"radius": 0.75, "softness": 0.7, "color": (0.05, 0.03, 0.02)}),
    ],
}


def main(argv=None):
    session.load_penumbra().register()
    from penumbra.operators.presets import SHIPPED_DIR, preset_source

    scene = scenes.empty_scene(8, 8)
    s = scene.penumbra
    SHIPPED_DIR.mkdir(parents=True, exist_ok=True)
    for name, stack in LOOKS.items():
        s.layers.clear()
        for effect, label, mix, params in stack:
            layer = s.layers.add()
            layer.effect, layer.name, layer.mix = effect, label, mix
            for key, value in params.items():
                setattr(layer.params(), key, value)
        path = SHIPPED_DIR / f"{name}.py"
        path.write_text(preset_source(s), encoding="utf-8")
        print(f"wrote {path}")


if __name__ == "__main__":
    session.run(main)
