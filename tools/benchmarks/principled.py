"""The Principled BSDF's input groups, one sphere each, against Cycles and EEVEE.

Each case is a sphere of radius 1 filling an orthographic view (64x64): its material a
Principled BSDF with one input group set (and the group's extremes), lit by a sun over a dim
grey world (``sun``) or by Blender's forest HDRI (``hdri``). Penumbra at ``--samples`` (64) and
EEVEE (16) are compared with Cycles at ``--reference`` spp (1024; direct light, which the
world's light and the lights are, cached per clone under out/reference_cache). The error is the
display MAE (Standard view, sRGB-encoded, clipped to [0, 1]) over the pixels whose centre sees
the sphere (its disc, analytically).

Cases: ``base`` (no group: the reference of the rest), ``coat r0`` and ``coat r1`` (Coat Weight 1
at Coat Roughness 0 and 1, over a red rough dielectric), ``coat tint`` (an orange tint at
roughness 0.1), ``metal`` (a rough gold, no coat) and ``coat on metal`` (Coat 1 at roughness
0.05 over it), ``coat half``
(Coat Weight 0.5 at roughness 0.3), ``film 0`` and ``film 300`` (a near-black glossy dielectric
without and with a 300 nm Thin Film of IOR 1.33), ``film 600 on metal`` (a half-metallic white
under a 600 nm film of IOR 1.6), ``sheen 0``, ``sheen 0.3`` and ``sheen 1 on black`` (Sheen Weight 1
at Sheen Roughness 0, 0.3 and 1 over a black base: the sheen alone), ``sheen tint`` (a blue tint at
roughness 0.5 over the red base) and ``sheen under coat`` (the same untinted, under Coat 1 at
roughness 0.1); ``aniso 1``, ``aniso 0.5 turned`` (Anisotropic Rotation 0.25) and ``aniso 1 rough 1`` (a
brushed white metal of roughness 0.4 or 1, its tangent Cycles' radial one about the sphere's Z)
and ``aniso 1 on plastic`` (the red base at roughness 0.3); ``subsurface 0``, ``subsurface`` and
``subsurface large`` (a skin-coloured base of Subsurface Weight 1, the default Radius at Scale 0,
0.1 and 1, Random Walk) and ``subsurface burley`` (Scale 1, Christensen-Burley), lit from the side
(``side``: half the sphere the camera sees) and by the HDRI. Writes ``<out>/principled.csv`` and a
Markdown table to stdout; ``--sheet PATH`` draws the spheres into a PNG.
``--quick``: reference 256 spp.
"""

import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import report, scenes, session
from devkit.engines import EEVEE_SAMPLES, configure
from devkit.reflection_scenes import hdri_path
from devkit.render import cached_image, render
from devkit.world_scenes import display

SKIN = (0.8, 0.45, 0.3, 1.0)
HELP = "the Principled BSDF's input groups on spheres vs Cycles and EEVEE -> <out>/principled.csv"

SIZE = 64
CSV_FIELDS = ["case", "light", "penumbra", "eevee", "penumbra_s", "eevee_s"]

# name -> the Principled inputs set (besides a red rough dielectric base)
CASES = {
    "base": {},
    "coat r0": {"Coat Weight": 1.0, "Coat Roughness": 0.0},
    "coat r1": {"Coat Weight": 1.0, "Coat Roughness": 1.0},
    "coat tint": {"Coat Weight": 1.0, "Coat Roughness": 0.1, "Coat Tint": (1.0, 0.55, 0.2, 1.0)},
    "metal": {"Base Color": (1.0, 0.78, 0.34, 1.0), "Metallic": 1.0, "Roughness": 0.45},
    "coat on metal": {
        "Base Color": (1.0, 0.78, 0.34, 1.0),
        "Metallic": 1.0,
        "Roughness": 0.45,
        "Coat Weight": 1.0,
        "Coat Roughness": 0.05,
    },
    "coat half": {"Coat Weight": 0.5, "Coat Roughness": 0.3},
    "film 0": {"Base Color": (0.02, 0.02, 0.02, 1.0), "Roughness": 0.2},
    "film 300": {"Base Color": (0.02, 0.02, 0.02, 1.0), "Roughness": 0.2, "Thin Film Thickness": 300.0},
    "film 600 on metal": {
        "Base Color": (0.9, 0.9, 0.9, 1.0),
        "Metallic": 0.5,
        "Roughness": 0.2,
        "Thin Film Thickness": 600.0,
        "Thin Film IOR": 1.6,
    },
    "sheen 0 on black": {"Base Color": (0.0, 0.0, 0.0, 1.0), "Sheen Weight": 1.0, "Sheen Roughness": 0.0},
    "sheen 0.3 on black": {"Base Color": (0.0, 0.0, 0.0, 1.0), "Sheen Weight": 1.0, "Sheen Roughness": 0.3},
    "sheen 1 on black": {"Base Color": (0.0, 0.0, 0.0, 1.0), "Sheen Weight": 1.0, "Sheen Roughness": 1.0},
    "sheen tint": {"Sheen Weight": 1.0, "Sheen Roughness": 0.5, "Sheen Tint": (0.3, 0.6, 1.0, 1.0)},
    "sheen under coat": {"Sheen Weight": 1.0, "Sheen Roughness": 0.5, "Coat Weight": 1.0, "Coat Roughness": 0.1},
    "aniso 1": {"Base Color": (0.9, 0.9, 0.9, 1.0), "Metallic": 1.0, "Roughness": 0.4, "Anisotropic": 1.0},
    "aniso 0.5 turned": {
        "Base Color": (0.9, 0.9, 0.9, 1.0),
        "Metallic": 1.0,
        "Roughness": 0.4,
        "Anisotropic": 0.5,
        "Anisotropic Rotation": 0.25,
    },
    "aniso 1 rough 1": {"Base Color": (0.9, 0.9, 0.9, 1.0), "Metallic": 1.0, "Roughness": 1.0, "Anisotropic": 1.0},
    "aniso 1 on plastic": {"Roughness": 0.3, "Anisotropic": 1.0},
    "subsurface 0": {"Base Color": SKIN, "Subsurface Weight": 1.0, "Subsurface Scale": 0.0},
    "subsurface": {"Base Color": SKIN, "Subsurface Weight": 1.0, "Subsurface Scale": 0.1},
    "subsurface large": {"Base Color": SKIN, "Subsurface Weight": 1.0, "Subsurface Scale": 1.0},
    "subsurface burley": {
        "Base Color": SKIN,
        "Subsurface Weight": 1.0,
        "Subsurface Scale": 1.0,
        "method": "BURLEY",
    },
}
LIGHTS = ("sun", "hdri")
# The subsurface cases' sun lights the sphere from the side (half of what the camera sees):
# their light spreads across the terminator.
CASE_LIGHTS = {name: ("side", "hdri") for name in CASES if name.startswith("subsurface")}


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    parser.add_argument("--quick", action="store_true", help="reference 256 spp")
    parser.add_argument("--samples", type=int, default=64, help="Penumbra's render samples (default 64)")
    parser.add_argument("--reference", type=int, default=1024, help="Cycles' reference spp (default 1024)")
    parser.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + ", ".join(CASES))
    parser.add_argument("--sheet", type=Path, help="also draw the spheres (Cycles, Penumbra, EEVEE) into this PNG")


def log(message):
    print(f"bench principled: {message}", file=sys.stderr, flush=True)


def sphere_scene(case, light):
    """The sphere of ``case`` under ``light`` ("sun" or "hdri")."""
    scene = scenes.empty_scene(SIZE, SIZE)
    scene.render.filter_size = scene.penumbra.filter_size = 1.5
    mat = scenes.material("Sphere", (0.6, 0.08, 0.06), roughness=0.5)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for name, value in CASES[case].items():
        if name == "method":
            bsdf.subsurface_method = value
        else:
            bsdf.inputs[name].default_value = value
    scenes.uv_sphere(scene, "Sphere", radius=1.0, segments=96, rings=48, mat=mat)
    scenes.camera(scene, (0.0, -10.0, 0.0), (np.pi / 2, 0.0, 0.0), ortho_scale=2.2, clip=(0.1, 20.0))
    if light in ("sun", "side"):
        scenes.set_world(scene, (0.05, 0.05, 0.06))
        rotation = (0.9, 0.3, -0.6) if light == "sun" else (0.0, np.pi / 2, 0.0)
        scenes.light(scene, "Sun", "SUN", 3.0, rotation=rotation, angle=0.02)
    else:
        tree = scene.world.node_tree
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.load(str(hdri_path()))
        background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
        tree.links.new(env.outputs[0], background.inputs["Color"])
    return scene


def sphere_mask():
    """The pixels whose centre sees the sphere (radius 1 in an orthographic view 2.2 wide),
    rows from the bottom."""
    c = (np.arange(SIZE) + 0.5) / SIZE * 2.2 - 1.1
    x, z = np.meshgrid(c, c)
    return x * x + z * z < 0.97 * 0.97  # off the silhouette's antialiased edge


def cycles(scene, spp):
    configure(scene, "CYCLES", samples=spp)
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = scene.penumbra.filter_size


def reference(case, light, spp):
    def make():
        scene = sphere_scene(case, light)
        cycles(scene, spp)
        return display(render(scene)["Combined"])

    return cached_image("principled", __file__, f"{case}-{light}-{SIZE}-{spp}", make)


def timed(scene):
    start = time.perf_counter()
    image = display(render(scene)["Combined"])
    return image, time.perf_counter() - start


def draw_sheet(path, shown, spp, samples):
    """The spheres of ``shown`` [(case, light, {engine: display image}, row)] side by side:
    Cycles, Penumbra and EEVEE, and Penumbra's error x4."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    titles = (f"Cycles {spp} spp", f"Penumbra {samples}", f"EEVEE {EEVEE_SAMPLES}", "|Penumbra - Cycles| x4")
    fig, axes = plt.subplots(len(shown), 4, figsize=(7.2, 1.9 * len(shown)), dpi=100, squeeze=False)
    for r, (case, light, images, row) in enumerate(shown):
        tiles = (
            images["cycles"],
            images["penumbra"],
            images["eevee"],
            np.abs(images["penumbra"] - images["cycles"]) * 4,
        )
        for c, tile in enumerate(tiles):
            ax = axes[r, c]
            ax.imshow(np.clip(tile[::-1, :, :3], 0.0, 1.0), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(titles[c], fontsize=8)
        axes[r, 0].set_ylabel(f"{case}\n{light}", fontsize=8)
        axes[r, 1].set_xlabel(f"MAE {row['penumbra']:.4f}", fontsize=7)
        axes[r, 2].set_xlabel(f"MAE {row['eevee']:.4f}", fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def run(args):
    spp = 256 if args.quick else args.reference
    names = [n.strip() for n in args.cases.split(",") if n.strip()]
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    mask = sphere_mask()
    started = time.perf_counter()
    rows, shown = [], []
    with session.stdout_to_stderr():
        for case in names:
            for light in CASE_LIGHTS.get(case, LIGHTS):
                log(f"{case}, {light}")
                ref = reference(case, light, spp)
                scene = sphere_scene(case, light)
                configure(scene, "PENUMBRA", render_samples=args.samples)
                ours, ours_s = timed(scene)
                configure(scene, "EEVEE", taa_render_samples=EEVEE_SAMPLES)
                eevee, eevee_s = timed(scene)
                rows.append(
                    {
                        "case": case,
                        "light": light,
                        "penumbra": float(np.abs(ours - ref)[mask].mean()),
                        "eevee": float(np.abs(eevee - ref)[mask].mean()),
                        "penumbra_s": ours_s,
                        "eevee_s": eevee_s,
                    }
                )
                if args.sheet:
                    shown.append((case, light, {"cycles": ref, "penumbra": ours, "eevee": eevee}, rows[-1]))
    report.write_csv(args.out / "principled.csv", rows, CSV_FIELDS)
    if args.sheet:
        draw_sheet(args.sheet, shown, spp, args.samples)
    title = (
        f"Principled BSDF input groups on a sphere, {SIZE}x{SIZE}, display MAE over the sphere against Cycles "
        f"{spp} spp; Penumbra {args.samples} samples, EEVEE {EEVEE_SAMPLES}; Blender {bpy.app.version_string}"
    )
    cells = [
        [
            r["case"],
            r["light"],
            f"{r['penumbra']:.4f}",
            f"{r['eevee']:.4f}",
            f"{r['penumbra_s']:.2f}",
            f"{r['eevee_s']:.2f}",
        ]
        for r in rows
    ]
    print(f"### {title}\n")
    print(report.markdown_table(["Case", "Light", "Penumbra", "EEVEE", "Penumbra (s)", "EEVEE (s)"], cells))
    print(
        f"\nGPU: {session.gpu_renderer() or 'n/a'}; one render per engine and case; "
        f"{(time.perf_counter() - started) / 60:.1f} min. Wrote principled.csv."
    )
    return 0
