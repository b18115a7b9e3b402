"""Blender's passes from Penumbra against Cycles' (``features/passes.py``): on scenes of the
bench's own (not the suite's), each light and colour pass at ``--samples`` against Cycles at
``--cycles-samples`` with max bounces 0 (direct light only; the same Blackman-Harris window),
as the mean absolute error of the linear pass and of its display-referred image (sRGB, 0..1);
the per-pixel error of Cycles' algebra (the light passes times their colours plus Emission and
Environment, against Combined); and what asking for the passes costs: F12 medians of
``--runs`` renders with no further pass, the data passes, the light passes, Cryptomatte, as
ratios to the frame without (interleaved in one process)."""

import statistics
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np

from devkit import engines, imageio, report, scenes, session, timing
from devkit.world_scenes import display

HELP = "light and colour passes against Cycles' (max bounces 0), the passes' algebra and their cost"

LIGHT = (
    "diffuse_direct",
    "diffuse_indirect",
    "diffuse_color",
    "glossy_direct",
    "glossy_indirect",
    "glossy_color",
    "transmission_direct",
    "transmission_color",
    "emit",
    "environment",
)
DATA = ("position", "object_index", "material_index", "diffuse_color", "glossy_color", "environment")
ALL_SWITCHES = (*LIGHT, *DATA, "transmission_direct", "transmission_color", "diffuse_indirect", "glossy_indirect")


def add_arguments(parser):
    parser.add_argument("--out", default="out")
    parser.add_argument("--width", type=int, default=160)
    parser.add_argument("--height", type=int, default=90)
    parser.add_argument("--samples", type=int, default=64, help="Penumbra's render samples (default 64)")
    parser.add_argument("--cycles-samples", type=int, default=1024, help="Cycles' samples (default 1024)")
    parser.add_argument("--runs", type=int, default=5, help="timed renders of each cost case (default 5)")


def studio(width, height):
    """A red box, a copper ball and a grey floor under a sun and a blue-grey world."""
    scene = scenes.empty_scene(width, height)
    scenes.set_world(scene, (0.3, 0.35, 0.45))
    scenes.box(
        scene, "Box", center=(0.0, 0.0, 0.5), size=(1.0, 1.0, 1.0), mat=scenes.material("Red", (0.8, 0.1, 0.1), 0.4)
    )
    copper = scenes.material("Copper", (0.9, 0.6, 0.3), roughness=0.3, metallic=1.0)
    scenes.uv_sphere(scene, "Ball", center=(1.3, 0.5, 0.5), radius=0.5, mat=copper)
    scenes.box(scene, "Lamp", center=(0.2, -1.2, 0.15), size=(0.3, 0.3, 0.3), mat=scenes.emissive("Glow", 2.0))
    scenes.plane(scene, "Floor", size=10.0, mat=scenes.material("Grey", (0.5, 0.5, 0.5), roughness=0.5))
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.5, 0.2, 0.0))
    scenes.look_at(scene, (3.0, -3.5, 2.5), (0.0, 0.0, 0.4))
    return scene


def lamps(width, height):
    """Rough spheres of three colours lit by a spot and an area light, no world light."""
    scene = scenes.empty_scene(width, height)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    for i, color in enumerate(((0.7, 0.7, 0.2), (0.2, 0.6, 0.7), (0.8, 0.8, 0.8))):
        mat = scenes.material(f"Ball{i}", color, roughness=0.25 + 0.3 * i, specular=0.5)
        scenes.uv_sphere(scene, f"Ball{i}", center=(1.2 * (i - 1), 0.0, 0.5), radius=0.5, mat=mat)
    scenes.plane(scene, "Floor", size=10.0, mat=scenes.material("Floor", (0.6, 0.55, 0.5), roughness=0.6))
    spot = scenes.light(scene, "Spot", "SPOT", 400.0, location=(2.0, -2.0, 3.0), spot_size=1.0)
    scenes.aim(spot, (0.0, 0.0, 0.3))
    scenes.light(scene, "Panel", "AREA", 150.0, location=(-2.0, -1.0, 2.5), size=1.0)
    scenes.look_at(scene, (0.0, -4.0, 2.2), (0.0, 0.0, 0.4))
    return scene


SCENES = {"studio": studio, "lamps": lamps}


def _render(scene, path):
    imageio.set_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER", color_depth="32", exr_codec="ZIP")
    scene.render.filepath = str(path)
    scene.render.use_file_extension = False
    with session.stdout_to_stderr():
        bpy.ops.render.render(write_still=True)
    return imageio.read_exr(path)


def _switch(scene, names, on=True):
    layer = scene.view_layers[0]
    for name in names:
        setattr(layer, "use_pass_" + name, on)


def accuracy(args, tmp):
    """Per scene and pass: Penumbra's and Cycles' mean, MAE, display MAE; the algebra's error."""
    rows = []
    for name, build in SCENES.items():
        scene = build(args.width, args.height)
        _switch(scene, LIGHT)
        scene.penumbra.render_samples = args.samples
        ours = _render(scene, Path(tmp) / f"{name}_penumbra.exr")
        engines.configure(scene, "CYCLES", samples=args.cycles_samples, pixel_filter_type="BLACKMAN_HARRIS")
        scene.cycles.filter_width = scene.penumbra.filter_size
        theirs = _render(scene, Path(tmp) / f"{name}_cycles.exr")
        for key in ("Combined", "Diffuse Direct", "Diffuse Color", "Glossy Direct", "Glossy Color", "Emission",
                    "Environment"):  # fmt: skip
            a, b = _pass(ours, key), _pass(theirs, key)
            rows.append(
                {
                    "scene": name,
                    "pass": key,
                    "penumbra_mean": float(a.mean()),
                    "cycles_mean": float(b.mean()),
                    "mae": float(np.abs(a - b).mean()),
                    "display_mae": float(np.abs(display(a) - display(b)).mean()),
                }
            )
        total = sum(
            (_pass(ours, f"{k} Direct") + _pass(ours, f"{k} Indirect")) * _pass(ours, f"{k} Color")
            for k in ("Diffuse", "Glossy")
        )
        total = total + _pass(ours, "Transmission Direct") * _pass(ours, "Transmission Color")
        total = total + _pass(ours, "Emission") + _pass(ours, "Environment")
        rows.append(
            {
                "scene": name,
                "pass": "algebra (max per pixel)",
                "mae": float(np.abs(total - _pass(ours, "Combined")).max()),
            }
        )
        print(f"passes: {name} done", file=sys.stderr, flush=True)
    return rows


def _pass(data, key):
    aliases = {"Emission": "Emit", "Environment": "Env", "Diffuse Direct": "DiffDir", "Diffuse Color": "DiffCol",
               "Glossy Direct": "GlossDir", "Glossy Color": "GlossCol", "Diffuse Indirect": "DiffInd",
               "Glossy Indirect": "GlossInd", "Transmission Direct": "TransDir",
               "Transmission Color": "TransCol"}  # fmt: skip
    found = data.get(key, data.get(aliases.get(key, key)))
    return np.asarray(found, np.float64)[..., :3]


def cost(args, tmp):
    """F12 medians of the studio scene: no further pass, data passes, light passes, Cryptomatte."""
    scene = studio(args.width, args.height)
    scene.penumbra.render_samples = 16
    cases = {
        "no further pass": (),
        "data and colour passes": DATA,
        "light passes": LIGHT,
        "Cryptomatte (object, material)": ("cryptomatte_object", "cryptomatte_material"),
    }

    def frame(names):
        _switch(scene, ALL_SWITCHES + ("cryptomatte_object", "cryptomatte_material"), False)
        _switch(scene, names)
        with session.stdout_to_stderr():
            bpy.ops.render.render(write_still=False)

    times = {case: [] for case in cases}
    for names in cases.values():
        frame(names)  # programs compiled
    for _ in range(args.runs):
        for case, names in cases.items():
            times[case].append(timing.measure(lambda n=names: frame(n), 1, warmup=0).times[0])
    base = statistics.median(times["no further pass"])
    return [
        {"case": case, "median_ms": statistics.median(t) * 1000, "ratio": statistics.median(t) / base}
        for case, t in times.items()
    ]


def run(args):
    session.load_penumbra().register()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        rows = accuracy(args, tmp)
        costs = cost(args, tmp)
    report.write_csv(out / "passes.csv", rows, ["scene", "pass", "penumbra_mean", "cycles_mean", "mae", "display_mae"])
    report.write_csv(out / "passes_cost.csv", costs, ["case", "median_ms", "ratio"])
    table = [
        [r["scene"], r["pass"], report.cell(r.get("penumbra_mean"), 4), report.cell(r.get("cycles_mean"), 4),
         report.cell(r["mae"], 3), report.cell(r.get("display_mae"), 3)]
        for r in rows
    ]  # fmt: skip
    print(report.markdown_table(["scene", "pass", "Penumbra mean", "Cycles mean", "MAE", "display MAE"], table))
    print()
    print(
        report.markdown_table(
            ["case", "F12 median (ms)", "ratio"],
            [[c["case"], f"{c['median_ms']:.0f}", f"{c['ratio']:.2f}"] for c in costs],
        )
    )
    print(
        f"\n{bpy.app.version_string}; {args.width}x{args.height}; Penumbra {args.samples} samples (cost: 16), "
        f"Cycles {args.cycles_samples} samples, max bounces 0; cost: medians of {args.runs} interleaved F12 renders."
    )
    return 0
