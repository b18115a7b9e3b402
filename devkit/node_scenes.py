"""Scenes for testing compiled shader nodes: a grid of unit planes seen from straight above by
an orthographic camera, each pixel block one plane, each plane its own material whose
Emission shader (Strength 1) the node under test drives. The world is black and there is no
light, so a pixel is what the node gives (scene-linear, 'Standard' view transform).

``grid(count, block)`` -> ``Grid``; ``Grid.uv()`` gives every pixel's analytic UV and plane
index, so a numpy reference (``devkit.node_reference``) can be evaluated at each pixel.
Pixel rows run from the bottom (Blender's order); plane i sits at column i % cols, row
i // cols; its UV map is (x, y) mapped to [0, 1] over the plane.
"""

import math
from dataclasses import dataclass

import bpy
import numpy as np

from devkit import material_scenes, scenes


@dataclass
class Cell:
    ob: object
    mat: object
    nodes: object
    links: object
    emission: object  # the Emission node: drive inputs["Color"]
    output: object


@dataclass
class Grid:
    scene: object
    cells: list
    cols: int
    rows: int
    block: int

    def uv(self):
        """(u, v, plane index) per pixel, each (rows * block, cols * block)."""
        h, w = self.rows * self.block, self.cols * self.block
        r, c = np.mgrid[0:h, 0:w]
        u = (c % self.block + 0.5) / self.block
        v = (r % self.block + 0.5) / self.block
        index = (r // self.block) * self.cols + c // self.block
        return u, v, index


def emission_material(name):
    """A material whose surface is an Emission shader (Strength 1): (mat, nodes, links,
    emission, output)."""
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:
        mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 1.0
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return mat, nodes, links, emission, output


def grid(count, block=8, world=(0.0, 0.0, 0.0)):
    """``count`` emission planes in a near-square grid of ``block`` pixels each."""
    cols = max(1, math.ceil(math.sqrt(count)))
    rows = max(1, math.ceil(count / cols))
    scene = scenes.empty_scene(cols * block, rows * block, engine=material_scenes.default_engine())
    scenes.set_world(scene, world)
    scenes.top_camera(scene, height=10.0, ortho_scale=float(max(cols, rows)))
    cells = []
    for i in range(count):
        mat, nodes, links, emission, output = emission_material(f"Node{i:03d}")
        ob = material_scenes.uv_plane(scene, f"Plane{i:03d}", size=1.0, mat=mat)
        ob.location = ((i % cols) + 0.5 - cols / 2.0, (i // cols) + 0.5 - rows / 2.0, 0.0)
        cells.append(Cell(ob, mat, nodes, links, emission, output))
    return Grid(scene, cells, cols, rows, block)


def uv_input(cell, axis, scale=1.0, offset=0.0):
    """A node socket giving ``uv[axis] * scale + offset`` (Texture Coordinate UV -> Separate
    XYZ -> Math Multiply Add): the output socket."""
    nodes, links = cell.nodes, cell.links
    coords = nodes.new("ShaderNodeTexCoord")
    sep = nodes.new("ShaderNodeSeparateXYZ")
    links.new(coords.outputs["UV"], sep.inputs["Vector"])
    mad = nodes.new("ShaderNodeMath")
    mad.operation = "MULTIPLY_ADD"
    links.new(sep.outputs["XYZ"[axis]], mad.inputs[0])
    mad.inputs[1].default_value = scale
    mad.inputs[2].default_value = offset
    return mad.outputs[0]


def sphere(width, height, build, name="Asset"):
    """``material_scenes.sphere_view`` (a smooth unit sphere, a sun from the upper left, the
    dim grey world) with a material whose tree ``build(mat, nodes, links, bsdf, output)``
    makes from the default Principled BSDF and Material Output."""
    scene = material_scenes.base(width, height)
    mat, bsdf, output = material_scenes.node_material(name)
    build(mat, mat.node_tree.nodes, mat.node_tree.links, bsdf, output)
    return material_scenes.sphere_view(scene, mat)


def shader_group(name, inputs, build):
    """A node group with float/colour ``inputs`` ((name, socket type, default)) and one Shader
    output, which ``build(tree, group_input, group_output)`` fills."""
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    for sock_name, kind, default in inputs:
        item = tree.interface.new_socket(sock_name, in_out="INPUT", socket_type=kind)
        if default is not None:
            item.default_value = default
    tree.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
    gin, gout = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    build(tree, gin, gout)
    return tree


def compiled_sphere(width, height):
    """``sphere`` with a tree only the compiler reads: a Mix Shader whose factor is a Checker
    (Generated, Scale 4) of the Principled BSDF (Base Color from a Color Ramp of a Gradient)
    and an Emission whose strength is Layer Weight's Facing."""

    def build(mat, nodes, links, bsdf, output):
        grad, ramp = nodes.new("ShaderNodeTexGradient"), nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = (0.8, 0.2, 0.1, 1.0)
        ramp.color_ramp.elements[1].color = (0.1, 0.4, 0.9, 1.0)
        links.new(grad.outputs["Fac"], ramp.inputs[0])
        links.new(ramp.outputs[0], bsdf.inputs["Base Color"])
        emission, weight = nodes.new("ShaderNodeEmission"), nodes.new("ShaderNodeLayerWeight")
        links.new(weight.outputs["Facing"], emission.inputs["Strength"])
        checker, mix = nodes.new("ShaderNodeTexChecker"), nodes.new("ShaderNodeMixShader")
        checker.inputs["Scale"].default_value = 4.0
        links.new(checker.outputs["Fac"], mix.inputs[0])
        links.new(bsdf.outputs[0], mix.inputs[1])
        links.new(emission.outputs[0], mix.inputs[2])
        links.new(mix.outputs[0], output.inputs["Surface"])

    return sphere(width, height, build, name="Compiled")
