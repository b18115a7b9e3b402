"""Participating media as Cycles defines them: what a World › Volume or a mesh material's Volume
output holds, read into per-unit-length coefficients (``Medium``) that the frame's volumes
technique integrates (``frame/features/volumes.py``).

Cycles' volume closures, per unit of length and per colour channel:

* Volume Scatter: scattering ``Color * Density`` (its extinction too), Henyey-Greenstein of
  its Anisotropy;
* Volume Absorption: absorption ``(1 - Color) * Density``;
* Principled Volume: scattering ``Color * Density``, absorption
  ``max(1 - Color, 0) * max(1 - sqrt(Absorption Color), 0) * Density``, emission
  ``Emission Strength * Emission Color`` (radiance per unit of length, not scaled by density);
* Emission into a Volume socket: ``Color * Strength`` per unit of length;
* Add Shader sums, Mix Shader blends by its factor (a constant one).

A medium is homogeneous: an input fed by another node (a texture, an attribute, a grid) is
drawn at the socket's own value, and the medium's message says so; so are Blackbody and the
phase functions other than Henyey-Greenstein (drawn as it, with their anisotropy)."""

import math
from dataclasses import dataclass, field

import numpy as np

from .sockets import source as _source

# A medium thinner than this (extinction and emission per unit of length, every channel) is
# nothing at all: it is not marched.
NEGLIGIBLE = 1e-12


@dataclass
class Medium:
    """One homogeneous medium: ``scatter`` and ``absorb`` (RGB, per unit of length; their sum is
    the extinction), ``emission`` (RGB radiance per unit of length), ``anisotropy`` (the
    Henyey-Greenstein g of its scattering, in [-0.99, 0.99]). ``kind``: "WORLD" (the world's:
    everything to the camera's clip end) or "BOX" (a mesh's interior: the box ``matrix`` maps
    [-1, 1]^3 onto, in world space). ``name``: what it came from; ``messages``: what it does
    not draw."""

    scatter: np.ndarray = field(default_factory=lambda: np.zeros(3))
    absorb: np.ndarray = field(default_factory=lambda: np.zeros(3))
    emission: np.ndarray = field(default_factory=lambda: np.zeros(3))
    anisotropy: float = 0.0
    kind: str = "WORLD"
    matrix: np.ndarray = field(default_factory=lambda: np.eye(4))
    name: str = ""
    messages: tuple = ()

    @property
    def extinction(self):
        return self.scatter + self.absorb

    @property
    def empty(self):
        """Nothing to draw: it neither attenuates nor emits."""
        return not (np.any(self.extinction > NEGLIGIBLE) or np.any(self.emission > NEGLIGIBLE))

    def placed(self, kind, matrix, name):
        """This medium's coefficients in the box ``matrix`` (or the world's, ``kind`` "WORLD")."""
        return Medium(
            self.scatter.copy(),
            self.absorb.copy(),
            self.emission.copy(),
            self.anisotropy,
            kind,
            np.asarray(matrix, np.float64),
            name,
            self.messages,
        )


def _finite(values, low=0.0, high=1e6):
    """Non-negative, finite coefficients: NaN reads as 0, anything past ``high`` as ``high``."""
    a = np.nan_to_num(np.asarray(values, np.float64), nan=0.0, posinf=high, neginf=low)
    return np.clip(a, low, high)


def _const(node, name, notes, label):
    """The value of ``node``'s input ``name`` (its own value where another node feeds it; then
    named once in ``notes``)."""
    socket = node.inputs.get(name) if hasattr(node.inputs, "get") else None
    if socket is None:
        return None
    if socket.is_linked:
        notes.append(f"{label}its {node.bl_label} {name} is fed by a node; drawn at the socket's own value")
    value = socket.default_value
    try:
        return np.array(value[:3], np.float64)
    except TypeError:
        return float(value)


def _scatter(node, notes, label):
    color = _finite(_const(node, "Color", notes, label), 0.0, 1e6)
    density = float(_finite(_const(node, "Density", notes, label)))
    g = float(_const(node, "Anisotropy", notes, label) or 0.0)
    phase = getattr(node, "phase", "HENYEY_GREENSTEIN")
    if phase not in {"HENYEY_GREENSTEIN", None}:
        notes.append(f"{label}its {phase.replace('_', ' ').title()} phase is drawn as Henyey-Greenstein")
    m = Medium(scatter=color * density)
    m.anisotropy = g
    return m


def _absorption(node, notes, label):
    color = _finite(_const(node, "Color", notes, label), 0.0, 1e6)
    density = float(_finite(_const(node, "Density", notes, label)))
    return Medium(absorb=np.maximum(1.0 - color, 0.0) * density)


def _principled(node, notes, label):
    color = _finite(_const(node, "Color", notes, label))
    density = float(_finite(_const(node, "Density", notes, label)))
    absorption_color = _finite(_const(node, "Absorption Color", notes, label))
    strength = float(_finite(_const(node, "Emission Strength", notes, label)))
    emission_color = _finite(_const(node, "Emission Color", notes, label))
    blackbody = float(_finite(_const(node, "Blackbody Intensity", notes, label)))
    if blackbody > 1e-3:
        notes.append(f"{label}its Blackbody emission is not drawn")
    m = Medium(
        scatter=color * density,
        absorb=np.maximum(1.0 - color, 0.0) * np.maximum(1.0 - np.sqrt(absorption_color), 0.0) * density,
        emission=emission_color * strength if strength > 1e-5 else np.zeros(3),
    )
    m.anisotropy = float(_const(node, "Anisotropy", notes, label) or 0.0)
    return m


def _emission(node, notes, label):
    color = _finite(_const(node, "Color", notes, label))
    strength = float(_finite(_const(node, "Strength", notes, label)))
    return Medium(emission=color * strength)


def _mix(media, weights):
    """The media summed with ``weights``; the anisotropy is their scattering's weighted mean."""
    out = Medium()
    g_weight = 0.0
    for m, w in zip(media, weights, strict=True):
        out.scatter = out.scatter + w * m.scatter
        out.absorb = out.absorb + w * m.absorb
        out.emission = out.emission + w * m.emission
        s = w * float(np.mean(m.scatter))
        out.anisotropy += s * m.anisotropy
        g_weight += s
    out.anisotropy = out.anisotropy / g_weight if g_weight > 0.0 else 0.0
    return out


def _read(node, notes, label, depth=0):
    """The medium of the volume shader ``node`` (None where nothing reaches it)."""
    if node is None or depth > 32:
        return None
    kind = node.bl_idname
    if kind == "ShaderNodeVolumeScatter":
        return _scatter(node, notes, label)
    if kind == "ShaderNodeVolumeAbsorption":
        return _absorption(node, notes, label)
    if kind == "ShaderNodeVolumePrincipled":
        return _principled(node, notes, label)
    if kind == "ShaderNodeEmission":
        return _emission(node, notes, label)
    if kind == "ShaderNodeAddShader":
        parts = [_read(_source(s)[0], notes, label, depth + 1) for s in node.inputs[:2]]
        parts = [p for p in parts if p is not None]
        return _mix(parts, [1.0] * len(parts)) if parts else None
    if kind == "ShaderNodeMixShader":
        fac = float(np.clip(_finite(_const(node, "Fac", notes, label)), 0.0, 1.0))
        a = _read(_source(node.inputs[1])[0], notes, label, depth + 1)
        b = _read(_source(node.inputs[2])[0], notes, label, depth + 1)
        parts = [(p, w) for p, w in ((a, 1.0 - fac), (b, fac)) if p is not None]
        return _mix([p for p, _ in parts], [w for _, w in parts]) if parts else None
    notes.append(f"{label}its '{node.bl_label}' node is not a volume shader Penumbra draws")
    return None


def medium_of(tree, output_idname, label, targets=None):
    """The ``Medium`` the active ``output_idname`` node of ``tree`` has on its Volume socket,
    or None when nothing is linked there (or it neither attenuates nor emits)."""
    outputs = [n for n in tree.nodes if n.bl_idname == output_idname]
    active = [n for n in outputs if n.is_active_output and (targets is None or n.target in targets)] or outputs
    for out in active:
        if "Volume" not in out.inputs:
            continue
        node, _ = _source(out.inputs["Volume"])
        if node is None:
            continue
        notes = []
        medium = _read(node, notes, label)
        if medium is None:
            return Medium(messages=tuple(dict.fromkeys(notes)))
        medium.anisotropy = float(np.clip(medium.anisotropy if math.isfinite(medium.anisotropy) else 0.0, -0.99, 0.99))
        medium.messages = tuple(dict.fromkeys(notes))
        return medium
    return None


def is_box(mesh):
    """Whether ``mesh`` is a box (8 vertices, 6 faces): its interior is its bounding box."""
    try:
        return len(mesh.vertices) == 8 and len(mesh.polygons) == 6
    except AttributeError:
        return False


def box_matrix(matrix_world, bound_box):
    """The 4x4 map of [-1, 1]^3 onto an object's bounding box (local ``bound_box`` corners,
    8 x 3) placed by ``matrix_world``; None where the box is flat or not finite."""
    c = np.asarray(bound_box, np.float64).reshape(8, 3)
    lo, hi = c.min(axis=0), c.max(axis=0)
    half = 0.5 * (hi - lo)
    if not (np.all(np.isfinite(half)) and np.all(half > 0.0)):
        return None
    local = np.diag([*half, 1.0])
    local[:3, 3] = 0.5 * (hi + lo)
    out = np.asarray(matrix_world, np.float64) @ local
    if not np.all(np.isfinite(out)) or abs(np.linalg.det(out[:3, :3])) < 1e-30:
        return None
    return out
