"""Write the glTF test assets of ``devkit/gltf/`` (see the README there), deterministically,
with Blender's own glTF exporter:

    .venv/blender-5.2/bin/python -m tools.make_assets [--out devkit/gltf]

Each asset is Keenan Crane's "Spot" (``devkit/meshes/spot.npz``, CC0), smooth-shaded, on its
own UV layout, with textures computed here in numpy (no photograph, nothing downloaded):

spot_pbr          metal-roughness: base colour, metallic-roughness (G roughness, B metal),
                  tangent-space normal, emissive and occlusion maps
spot_alpha        an alpha-blended glass bubble round the head (alpha from a texture) and an
                  alpha-clipped card with a cut-out pattern (cutoff 0.5) behind the cow
spot_specgloss    KHR_materials_pbrSpecularGlossiness: diffuse and specular-glossiness maps
                  (coloured specular on the patches, dielectric 0.04 elsewhere); Blender's
                  exporter cannot write this extension, so the file it writes is rewritten
spot_lines        thin emissive lines one texel wide and a fine normal ripple, glossy

Textures are small (64² to 256²) and the meshes carry no tangents, so each file stays well
under 1 MiB. Running this again writes the same bytes (on the same Blender line).
"""

import argparse
import json
import math
import struct
import tempfile
from pathlib import Path

import numpy as np

from devkit import session

OUT = Path(__file__).resolve().parent.parent / "devkit" / "gltf"
ASSETS = ("spot_pbr", "spot_alpha", "spot_specgloss", "spot_lines")


# --- textures (numpy, row 0 at the bottom as Blender's pixel buffers) --------------------------


def smooth_noise(size, cells, seed, channels=1):
    """Smooth value noise in [0, 1]: a ``cells``² random grid, bicubically (smoothstep)
    interpolated to ``size``², tiling."""
    rng = np.random.default_rng(seed)
    grid = rng.random((cells, cells, channels))
    t = np.arange(size) * cells / size
    i = np.floor(t).astype(int)
    f = t - i
    f = f * f * (3.0 - 2.0 * f)
    i0, i1 = i % cells, (i + 1) % cells
    rows = grid[i0] * (1 - f)[:, None, None] + grid[i1] * f[:, None, None]
    return rows[:, i0] * (1 - f)[None, :, None] + rows[:, i1] * f[None, :, None]


def uv_grid(size):
    """(u, v) of each texel centre, shape (size, size): rows are v, columns u."""
    c = (np.arange(size) + 0.5) / size
    return np.meshgrid(c, c)


def normal_from_height(height, strength):
    """Tangent-space normal map (0..1 encoded) of a tiling height field in texels."""
    dx = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) * 0.5 * strength
    dy = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) * 0.5 * strength
    n = np.stack([-dx, -dy, np.ones_like(height)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return n * 0.5 + 0.5


def patches(size, seed):
    """Spot-like patches: 1 inside a patch, 0 outside, softened over about a texel."""
    n = smooth_noise(size, 6, seed)[..., 0]
    return np.clip((n - 0.55) * size / 8.0, 0.0, 1.0)


def image(name, rgba, colorspace="sRGB"):
    """A Blender image from float RGBA (or RGB) ``rgba`` of shape (h, w, c), row 0 at the
    bottom, quantised to 8 bits as the PNG the exporter writes will be."""
    import bpy

    h, w, c = rgba.shape
    if c == 3:
        rgba = np.concatenate([rgba, np.ones((h, w, 1))], axis=-1)
    img = bpy.data.images.new(name, w, h, alpha=True)
    img.pixels.foreach_set((np.round(np.clip(rgba, 0.0, 1.0) * 255.0) / 255.0).astype(np.float32).ravel())
    # Saved as a PNG and packed: the exporter copies a packed PNG's bytes into the file (a
    # generated image it would make again from its generator settings, blank).
    with tempfile.TemporaryDirectory() as tmp:
        img.filepath_raw = str(Path(tmp) / f"{name}.png")
        img.file_format = "PNG"
        img.save()
        img.source = "FILE"
        img.reload()
        img.pack()
    img.colorspace_settings.name = colorspace
    return img


# --- materials -----------------------------------------------------------------------------


def principled(name):
    import bpy

    mat = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):
        mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    return mat, mat.node_tree, bsdf


def tex(tree, img, socket=None, output="Color"):
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = img
    if socket is not None:
        tree.links.new(node.outputs[output], socket)
    return node


def normal_map(tree, bsdf, img, strength=1.0):
    nmap = tree.nodes.new("ShaderNodeNormalMap")
    nmap.inputs["Strength"].default_value = strength
    tex(tree, img, nmap.inputs["Color"])
    tree.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])


def metal_roughness(tree, bsdf, img):
    sep = tree.nodes.new("ShaderNodeSeparateColor")
    tex(tree, img, sep.inputs["Color"])
    tree.links.new(sep.outputs["Green"], bsdf.inputs["Roughness"])
    tree.links.new(sep.outputs["Blue"], bsdf.inputs["Metallic"])


def occlusion(tree, img):
    """glTF's occlusion: an image into the exporter's "glTF Material Output" group (which
    nothing renders; the importer builds the same)."""
    import bpy

    name = "glTF Material Output"
    group = bpy.data.node_groups.get(name)
    if group is None:
        group = bpy.data.node_groups.new(name, "ShaderNodeTree")
        group.interface.new_socket("Occlusion", in_out="INPUT", socket_type="NodeSocketFloat")
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    sep = tree.nodes.new("ShaderNodeSeparateColor")
    tex(tree, img, sep.inputs["Color"])
    tree.links.new(sep.outputs["Red"], node.inputs["Occlusion"])


def emission(tree, bsdf, img, strength):
    tex(tree, img, bsdf.inputs["Emission Color"])
    bsdf.inputs["Emission Strength"].default_value = strength


# --- objects -------------------------------------------------------------------------------


def spot(scene, mat, name="Spot"):
    import bpy

    from devkit import assets  # imports bpy: after session.isolate()

    me = assets.mesh_from_file(assets.SPOT, name)
    me.shade_smooth()
    ob = bpy.data.objects.new(name, me)
    scene.collection.objects.link(ob)
    me.materials.append(mat)
    return ob


def grid_mesh(scene, name, mat, size, location, rotation, subdivisions=1):
    """A square in its local XY plane (UVs 0..1), placed by ``location`` and ``rotation``."""
    import bpy

    n = subdivisions + 1
    c = np.linspace(-size / 2, size / 2, n)
    xs, ys = np.meshgrid(c, c)
    verts = [(float(x), float(y), 0.0) for x, y in zip(xs.ravel(), ys.ravel(), strict=True)]
    cells = [(j * n + i, (j + 1) * n + i) for j in range(n - 1) for i in range(n - 1)]
    faces = [(a, a + 1, b + 1, b) for a, b in cells]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    uv = me.uv_layers.new(name="UVMap")
    for loop in me.loops:
        x, y, _ = verts[loop.vertex_index]
        uv.data[loop.index].uv = (x / size + 0.5, y / size + 0.5)
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    ob.location = location
    ob.rotation_euler = rotation
    scene.collection.objects.link(ob)
    return ob


def bubble(scene, name, mat, center, radius, segments=24, rings=12):
    """A smooth latitude-longitude sphere with UVs (u around, v from pole to pole)."""
    import bpy

    verts, faces, uvs = [], [], []
    for j in range(rings + 1):
        theta = math.pi * j / rings
        for i in range(segments + 1):  # the seam column twice, for its UVs
            phi = 2 * math.pi * i / segments
            ring = radius * math.sin(theta)
            verts.append((ring * math.cos(phi), ring * math.sin(phi), radius * math.cos(theta)))
    for j in range(rings):
        for i in range(segments):
            a, b = j * (segments + 1) + i, (j + 1) * (segments + 1) + i
            faces.append((a, b, b + 1, a + 1))
            uvs += [(i / segments, 1 - j / rings), (i / segments, 1 - (j + 1) / rings)]
            uvs += [((i + 1) / segments, 1 - (j + 1) / rings), ((i + 1) / segments, 1 - j / rings)]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.uv_layers.new(name="UVMap").data.foreach_set("uv", np.array(uvs, np.float32).ravel())
    me.shade_smooth()
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    ob.location = center
    scene.collection.objects.link(ob)
    return ob


# --- the assets ----------------------------------------------------------------------------


def build_pbr(scene):
    size = 128
    u, v = uv_grid(size)
    hide = patches(size, 11)[..., None]
    base = np.array([0.86, 0.84, 0.80]) * (1 - hide) + np.array([0.12, 0.10, 0.09]) * hide
    base = base * (0.9 + 0.1 * smooth_noise(size, 16, 12))
    metal = (smooth_noise(size, 4, 13)[..., 0] > 0.62).astype(float)
    rough = 0.25 + 0.5 * smooth_noise(size, 8, 14)[..., 0]
    ao = 0.6 + 0.4 * smooth_noise(size, 5, 15)[..., 0]
    mr = np.stack([ao, rough, metal], axis=-1)
    bumps = 0.5 + 0.5 * np.sin(u * 2 * math.pi * 12) * np.sin(v * 2 * math.pi * 12)
    spots = ((u * 8 % 1 - 0.5) ** 2 + (v * 8 % 1 - 0.5) ** 2 < 0.04) & (smooth_noise(size, 8, 16)[..., 0] > 0.6)
    glow = spots[..., None] * np.array([1.0, 0.45, 0.1])
    mat, tree, bsdf = principled("SpotPBR")
    tex(tree, image("spot_pbr_base", base), bsdf.inputs["Base Color"])
    orm = image("spot_pbr_orm", mr, "Non-Color")
    metal_roughness(tree, bsdf, orm)
    occlusion(tree, orm)
    normal_map(tree, bsdf, image("spot_pbr_normal", normal_from_height(bumps, 3.0), "Non-Color"))
    emission(tree, bsdf, image("spot_pbr_emissive", glow), 1.0)
    spot(scene, mat)


def build_alpha(scene):
    import bpy

    size = 64
    u, v = uv_grid(size)
    hide = patches(size, 21)[..., None]
    base = np.array([0.85, 0.82, 0.76]) * (1 - hide) + np.array([0.35, 0.18, 0.08]) * hide
    mat, tree, bsdf = principled("SpotHide")
    tex(tree, image("spot_alpha_base", base), bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.6
    spot(scene, mat)

    # Glass bubble: alpha from a texture (0.15 at the top to 0.6 at the rim band), blended.
    glass_rgba = np.empty((size, size, 4))
    glass_rgba[..., :3] = [0.55, 0.8, 1.0]
    glass_rgba[..., 3] = 0.15 + 0.45 * (np.abs(v - 0.5) < 0.08)
    glass, gtree, gbsdf = principled("Glass")
    node = tex(gtree, image("spot_alpha_glass", glass_rgba), gbsdf.inputs["Base Color"])
    gtree.links.new(node.outputs["Alpha"], gbsdf.inputs["Alpha"])
    gbsdf.inputs["Roughness"].default_value = 0.1
    if hasattr(glass, "surface_render_method"):
        glass.surface_render_method = "BLENDED"
    else:
        glass.blend_method = "BLEND"
    me = bpy.data.objects["Spot"].data
    co = np.empty(len(me.vertices) * 3)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    lo, hi = co.min(axis=0), co.max(axis=0)
    head = co[co[:, 1] > hi[1] - 0.25 * (hi[1] - lo[1])]  # Spot looks along +Y
    centre = tuple((head.min(axis=0) + head.max(axis=0)) / 2)
    bubble(scene, "Bubble", glass, centre, 0.62 * float(np.max(head.max(axis=0) - head.min(axis=0))))

    # Alpha-clipped card behind the cow: a lattice of round holes, cutoff 0.5.
    card_rgba = np.empty((size, size, 4))
    card_rgba[..., :3] = np.array([0.2, 0.55, 0.25]) * (0.8 + 0.2 * smooth_noise(size, 4, 22))
    holes = (u * 6 % 1 - 0.5) ** 2 + (v * 6 % 1 - 0.5) ** 2 < 0.12
    card_rgba[..., 3] = np.where(holes, 0.0, 1.0)
    card, ctree, cbsdf = principled("Lattice")
    node = tex(ctree, image("spot_alpha_lattice", card_rgba), cbsdf.inputs["Base Color"])
    clip = ctree.nodes.new("ShaderNodeMath")
    clip.operation = "ROUND"  # the exporter's alpha-clip idiom: cutoff 0.5
    ctree.links.new(node.outputs["Alpha"], clip.inputs[0])
    ctree.links.new(clip.outputs[0], cbsdf.inputs["Alpha"])
    height = float(hi[2] - lo[2])
    grid_mesh(
        scene,
        "Lattice",
        card,
        1.6 * height,
        (float(lo[0] + hi[0]) / 2, float(lo[1]) - 0.3 * height, float(lo[2]) + 0.8 * height),
        (math.pi / 2, 0.0, 0.0),
    )


def specgloss_image(size):
    """RGBA of the specular-glossiness map: RGB specular (a warm metal colour on the patches,
    0.04 grey elsewhere, sRGB as the extension has it), A glossiness."""
    hide = patches(size, 31)[..., None]
    spec = np.full((size, size, 3), 0.04) * (1 - hide) + np.array([0.95, 0.64, 0.37]) * hide
    spec = np.where(spec <= 0.0031308, spec * 12.92, 1.055 * spec ** (1 / 2.4) - 0.055)  # linear -> sRGB
    gloss = 0.45 + 0.35 * hide[..., 0] + 0.1 * smooth_noise(size, 8, 32)[..., 0]
    return np.concatenate([spec, gloss[..., None]], axis=-1), hide


def build_specgloss(scene):
    size = 128
    sg, hide = specgloss_image(size)
    diffuse = np.array([0.55, 0.5, 0.62]) * (1 - hide) + 0.02 * hide  # metals have no diffuse
    mat, tree, bsdf = principled("SpotSpecGloss")
    tex(tree, image("spot_sg_diffuse", diffuse), bsdf.inputs["Base Color"])
    # Only so the exporter writes the map into the file; rewrite_specgloss() replaces the link.
    tex(tree, image("spot_sg_specgloss", sg), bsdf.inputs["Specular Tint"])
    spot(scene, mat)


def build_lines(scene):
    size = 256
    u, v = uv_grid(size)
    iu, iv = np.meshgrid(np.arange(size), np.arange(size))
    lines = ((iu % 16 == 0) | (iv % 16 == 0)).astype(float)  # one texel wide
    glow = lines[..., None] * np.array([0.1, 0.9, 1.0])
    ripple = np.sin(iu * 2 * math.pi / 4) * 0.5 + np.sin((iu + iv) * 2 * math.pi / 6) * 0.5  # 4-6 texels
    base = np.full((size, size, 3), 0.25)
    mat, tree, bsdf = principled("SpotLines")
    tex(tree, image("spot_lines_base", base[:8, :8]), bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.3
    bsdf.inputs["Metallic"].default_value = 0.0
    normal_map(tree, bsdf, image("spot_lines_normal", normal_from_height(ripple, 0.6), "Non-Color"))
    emission(tree, bsdf, image("spot_lines_emissive", glow), 4.0)
    spot(scene, mat)


BUILDERS = {
    "spot_pbr": build_pbr,
    "spot_alpha": build_alpha,
    "spot_specgloss": build_specgloss,
    "spot_lines": build_lines,
}


# --- GLB post-processing -------------------------------------------------------------------


def read_glb(path):
    data = Path(path).read_bytes()
    magic, version, _length = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67 or version != 2:
        raise ValueError(f"{path}: not a glTF 2 binary")
    offset, chunks = 12, []
    while offset < len(data):
        size, kind = struct.unpack_from("<II", data, offset)
        chunks.append((kind, data[offset + 8 : offset + 8 + size]))
        offset += 8 + size
    doc = json.loads(chunks[0][1])
    binary = chunks[1][1] if len(chunks) > 1 else b""
    return doc, binary


def write_glb(path, doc, binary):
    text = json.dumps(doc, separators=(",", ":"), sort_keys=True).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    doc_chunk = struct.pack("<II", len(text), 0x4E4F534A) + text
    bin_chunk = struct.pack("<II", len(binary), 0x004E4942) + binary
    header = struct.pack("<III", 0x46546C67, 2, 12 + len(doc_chunk) + len(bin_chunk))
    Path(path).write_bytes(header + doc_chunk + bin_chunk)


def rewrite_specgloss(path):
    """Turn the exported metal-roughness material into KHR_materials_pbrSpecularGlossiness:
    diffuse = the base colour map, specular-glossiness = the map the exporter wrote for
    Specular Tint (written again here as RGBA, since the exporter drops its alpha)."""
    doc, binary = read_glb(path)
    mat = doc["materials"][0]
    pbr = mat.pop("pbrMetallicRoughness")
    tint = mat["extensions"].pop("KHR_materials_specular")["specularColorTexture"]
    for ext in ("KHR_materials_specular", "KHR_materials_ior"):
        mat["extensions"].pop(ext, None)
        for key in ("extensionsUsed", "extensionsRequired"):
            if ext in doc.get(key, []):
                doc[key].remove(ext)
    # Replace the tint image's bytes with the RGBA map (same texture, same sampler).
    source = doc["textures"][tint["index"]]["source"]
    with tempfile.TemporaryDirectory() as tmp:
        png = Path(tmp) / "sg.png"
        sg, _ = specgloss_image(128)
        write_png(png, sg)
        data = png.read_bytes()
    binary = binary + b"\0" * (-len(binary) % 4)
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(data)})
    binary += data
    doc["buffers"][0]["byteLength"] = len(binary)
    view = len(doc["bufferViews"]) - 1
    doc["images"][source] = {"bufferView": view, "mimeType": "image/png", "name": "spot_sg_specgloss"}
    mat.setdefault("extensions", {})["KHR_materials_pbrSpecularGlossiness"] = {
        "diffuseTexture": pbr["baseColorTexture"],
        "specularGlossinessTexture": {"index": tint["index"]},
        "specularFactor": [1.0, 1.0, 1.0],
        "glossinessFactor": 1.0,
    }
    doc.setdefault("extensionsUsed", []).append("KHR_materials_pbrSpecularGlossiness")
    # The previous image bytes stay in the buffer unreferenced: drop them to keep it small.
    write_glb(path, *compact(doc, binary))


def compact(doc, binary):
    """Drop buffer views nothing refers to and pack the others again, in order."""
    used = {a["bufferView"] for a in doc.get("accessors", []) if "bufferView" in a}
    used |= {i["bufferView"] for i in doc.get("images", []) if "bufferView" in i}
    views = doc["bufferViews"]
    remap, out, packed = {}, [], b""
    for index, view in enumerate(views):
        if index not in used:
            continue
        start = view.get("byteOffset", 0)
        chunk = binary[start : start + view["byteLength"]]
        packed += b"\0" * (-len(packed) % 4)
        view = dict(view, byteOffset=len(packed))
        packed += chunk
        remap[index] = len(out)
        out.append(view)
    doc["bufferViews"] = out
    for item in doc.get("accessors", []) + doc.get("images", []):
        if "bufferView" in item:
            item["bufferView"] = remap[item["bufferView"]]
    doc["buffers"][0]["byteLength"] = len(packed)
    return doc, packed


def write_png(path, rgba):
    """An 8-bit RGBA PNG of float ``rgba`` (row 0 at the bottom), through Blender's writer."""
    img = image(Path(path).stem, rgba, "Non-Color")
    img.filepath_raw = str(path)
    img.file_format = "PNG"
    img.save()


def export(name, out):
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    BUILDERS[name](scene)
    path = Path(out) / f"{name}.glb"
    with session.stdout_to_stderr():
        bpy.ops.export_scene.gltf(
            filepath=str(path),
            export_format="GLB",
            export_tangents=False,
            export_image_format="AUTO",
            export_apply=True,
            export_extras=False,
            export_cameras=False,
            export_lights=False,
            export_animations=False,
        )
    if name == "spot_specgloss":
        rewrite_specgloss(path)
    doc, binary = read_glb(path)
    doc["asset"]["copyright"] = "CC0 1.0: Spot by Keenan Crane; textures generated (tools/make_assets.py)"
    write_glb(path, doc, binary)
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--only", default="", help="comma-separated asset names (default: all)")
    args = parser.parse_args(argv)
    session.isolate()
    import bpy

    assert bpy.ops.preferences.addon_enable(module="io_scene_gltf2") == {"FINISHED"}
    args.out.mkdir(parents=True, exist_ok=True)
    for name in [n for n in args.only.split(",") if n] or ASSETS:
        path = export(name, args.out)
        print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    session.run(main)
