"""Scenes with participating media (engine/frame/features/volumes.py): volume materials, fog
boxes and a World › Volume, for the suite and ``tools.bench volumes``; and the analytic
references the suite holds them to (Beer-Lambert, the airlight integral)."""

import math

import bpy
import numpy as np

from devkit import scenes


def volume_material(name, kind="SCATTER", color=(0.8, 0.8, 0.8), density=1.0, anisotropy=0.0, **inputs):
    """A material with only a Volume output: a Volume Scatter ("SCATTER"), Volume Absorption
    ("ABSORB") or Principled Volume ("PRINCIPLED") node, with ``inputs`` set by name."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    tree = mat.node_tree
    for node in [n for n in tree.nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        tree.nodes.remove(node)
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    idname = {
        "SCATTER": "ShaderNodeVolumeScatter",
        "ABSORB": "ShaderNodeVolumeAbsorption",
        "PRINCIPLED": "ShaderNodeVolumePrincipled",
    }[kind]
    node = tree.nodes.new(idname)
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Density"].default_value = density
    if "Anisotropy" in node.inputs:
        node.inputs["Anisotropy"].default_value = anisotropy
    for key, value in inputs.items():
        node.inputs[key].default_value = value
    tree.links.new(node.outputs[0], out.inputs["Volume"])
    return mat


def world_volume(scene, color=(0.8, 0.8, 0.8), density=0.1, anisotropy=0.0):
    """A Volume Scatter on the scene world's Volume socket."""
    tree = scene.world.node_tree
    node = tree.nodes.new("ShaderNodeVolumeScatter")
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Density"].default_value = density
    node.inputs["Anisotropy"].default_value = anisotropy
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld")
    tree.links.new(node.outputs[0], out.inputs["Volume"])
    return node


def fog_box(scene, name="Fog", center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0), **material):
    """A box whose material is only a volume (``volume_material``)."""
    return scenes.box(scene, name, center=center, size=size, mat=volume_material(name, **material))


def slab_transmittance(extinction, thickness):
    """Beer-Lambert: what a homogeneous slab lets through straight across it."""
    return np.exp(-np.asarray(extinction, np.float64) * thickness)


def airlight(o, d, t0, t1, light, power, scatter, extinction, g=0.0, box=None, n=200001):
    """The single-scattered radiance along the ray ``o + t d`` (unit ``d``) over [t0, t1] in a
    homogeneous medium of ``scatter`` and ``extinction`` (per unit of length) lit by a point
    light of ``power`` watts (radius 0) at ``light``, Henyey-Greenstein ``g``: the airlight
    integral (Sun, Ramamoorthi, Narasimhan and Nayar 2005), here by the trapezoid rule over
    ``n`` points (exact to ~1e-8 of itself for the scenes of the suite). With ``box`` ((lo,
    hi) corners), the light's path counts only its length inside the box."""
    o, d, light = (np.asarray(v, np.float64) for v in (o, d, light))
    t = np.linspace(t0, t1, n)
    x = o + t[:, None] * d
    to = light - x
    dist = np.linalg.norm(to, axis=1)
    cos = np.einsum("ij,j->i", to, d) / dist
    phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * cos) ** 1.5)
    inside = dist if box is None else _inside_length(x, to / dist[:, None], dist, *box)
    tau_light = extinction * inside
    integrand = scatter * phase * power / (4 * math.pi * dist**2) * np.exp(-extinction * (t - t0) - tau_light)
    return float(np.trapezoid(integrand, t) if hasattr(np, "trapezoid") else np.trapz(integrand, t))


def _inside_length(x, u, tmax, lo, hi):
    """For rays x + s u, 0 <= s <= tmax (arrays), the length inside the box [lo, hi]."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (lo - x) / u
        b = (hi - x) / u
    s0 = np.nanmax(np.minimum(a, b), axis=1).clip(0.0)
    s1 = np.minimum(np.nanmin(np.maximum(a, b), axis=1), tmax)
    return np.maximum(s1 - s0, 0.0)
