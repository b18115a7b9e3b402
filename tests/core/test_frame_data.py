"""What a frame sends to the GPU, built without one: std140 packing against hand-derived
offsets, the lit pass's uniform data from a shadow plan, and the shaders' use of the structs."""

import dataclasses
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from devkit.session import ROOT, load_penumbra

load_penumbra()
from penumbra.engine import settings  # noqa: E402
from penumbra.engine.enums import LIGHT_TYPE, SHADOW_MODE  # noqa: E402
from penumbra.engine.frame import programs, shadow_programs  # noqa: E402
from penumbra.engine.frame.frame_data import AtlasShape, LitInputs, build_frame_data  # noqa: E402
from penumbra.engine.scene.extract import Camera, Light  # noqa: E402
from penumbra.engine.shadows import kernels, lightspace  # noqa: E402
from penumbra.engine.shadows import planning as shadows  # noqa: E402
from penumbra.shaders.loader import Struct  # noqa: E402


def test_std140_offsets_match_hand_derived_layout():
    s = Struct("T", (("FLOAT", "a"), ("VEC3", "b"), ("VEC2", "c"), ("INT", "d"), ("MAT4", "e"), ("IVEC2", "f")))
    # a at 0; vec3 aligns to 16 and takes 12 (16..28); vec2 aligns to 8 (32..40); int at 40;
    # mat4 aligns to 16 (48..112); ivec2 aligns to 8 (112..120); stride rounds up to 128.
    assert {k: v[0] for k, v in s.layout.items()} == {"a": 0, "b": 16, "c": 32, "d": 40, "e": 48, "f": 112}
    assert s.stride == 128
    assert "  vec3 b;\n" in s.glsl() and "  ivec2 f;\n" in s.glsl()


def test_pack_round_trips_floats_ints_and_column_major_matrices():
    s = Struct("T", (("VEC3", "v"), ("INT", "i"), ("MAT4", "m"), ("IVEC4", "t")))
    m = np.arange(16, dtype=np.float64).reshape(4, 4)
    data = s.pack([{"v": (1.5, -2, 3), "i": -1, "m": m, "t": (4, -1, 7, 48)}], count=3)
    assert data.shape == (3, s.stride // 4) and data.dtype == np.float32
    np.testing.assert_array_equal(s.unpack(data, 0, "v"), [1.5, -2, 3])
    assert s.unpack(data, 0, "i") == -1  # an int bit pattern, not the float -1.0
    assert data.view(np.int32)[0, 3] == -1
    np.testing.assert_array_equal(s.unpack(data, 0, "m"), m)
    np.testing.assert_array_equal(data[0, 4:8], m[:, 0])  # first column first
    np.testing.assert_array_equal(s.unpack(data, 0, "t"), [4, -1, 7, 48])
    assert not data[1:].any()  # elements past the rows are zero
    with pytest.raises(KeyError, match="missing"):
        s.pack([{"v": (0, 0, 0)}])
    with pytest.raises(KeyError, match="unknown"):
        s.pack([{"v": (0, 0, 0), "i": 0, "m": m, "t": (0, 0, 0, 0), "extra": 1}])


def test_pack_takes_every_kind_of_value_as_a_field_at_a_time_would():
    """The packer's two numpy writes a row (``Struct._plan``) against a field-by-field
    reference: numpy scalars, bools, arrays, half-way integers (rounded half to even) and, for
    a value of another length than its type (a VEC3 given 2 or 4 numbers), as many words from
    the field's first, as the packer wrote them before."""
    s = Struct("T", (("FLOAT", "f"), ("INT", "i"), ("VEC3", "v"), ("IVEC2", "k"), ("MAT4", "m"), ("INT", "j")))
    m = np.arange(16, dtype=np.float64).reshape(4, 4) * 0.5

    def reference(row):
        out = np.zeros(s.stride // 4, np.float32)
        ints = out.view(np.int32)
        for name, (off, typ) in s.layout.items():
            v = np.asarray(row[name], np.float64)
            v = (v.T if typ == "MAT4" else v).ravel()
            word = off // 4
            if typ in ("INT", "IVEC2"):
                ints[word : word + len(v)] = np.rint(v).astype(np.int32)
            else:
                out[word : word + len(v)] = v
        return out

    rows = [
        {"f": np.float32(0.1), "i": 2.5, "v": np.array([1e-40, -0.0, 3e38]), "k": (True, 3.5), "m": m, "j": -7},
        {"f": 1, "i": -2.5, "v": (1.0, 2.0), "k": np.array([1.5, -1.5]), "m": m.tolist(), "j": False},
        {"f": 0.5, "i": 7, "v": np.array([1.0, 2.0, 3.0, 4.0]), "k": (0, 0), "m": m, "j": 3},
    ]
    data = s.pack(rows)
    for k, row in enumerate(rows):
        np.testing.assert_array_equal(data[k].view(np.int32), reference(row).view(np.int32), err_msg=str(k))
    assert data.view(np.int32)[0, s.layout["i"][0] // 4] == 2  # 2.5 to the even neighbour
    assert data.view(np.int32)[1, s.layout["i"][0] // 4] == -2


def _settings(**overrides):
    source = SimpleNamespace(**{p.name: p.default for p in settings.SCENE_PARAMS})
    vars(source).update(overrides)
    return settings.render_settings(source)


def _camera():
    view = lightspace.look_at((0.0, -6.0, 3.0), (0.0, 1.0, -0.5))
    return Camera(view=view, projection=lightspace.perspective(math.radians(50), 16 / 9, 0.1, 100.0))


def _light(kind, position=(0.0, 0.0, 4.0), **kw):
    matrix = np.eye(4)
    matrix[:3, 3] = position
    return Light(type=kind, color=np.array([2.0, 1.0, 0.5]), matrix=matrix, radius=0.25, **kw)


def _plan(lights):
    """A real plan over a ground box and a caster box above it."""
    ground = lightspace.box_corners(np.array([-5.0, -5.0, -0.1]), np.array([5.0, 5.0, 0.0]))
    caster = lightspace.box_corners(np.array([-0.5, -0.5, 0.5]), np.array([0.5, 0.5, 1.5]))
    return shadows.plan_shadows(lights, np.stack([ground, caster]), shadows.MapOptions(256))


def test_frame_data_carries_every_light_its_tiles_and_the_settings():
    lights = [
        _light("SUN", angle=math.radians(10)),
        _light("POINT"),
        _light("SPOT", spot_size=math.radians(60), spot_blend=0.5),
        _light("SPOT", use_shadow=False),
    ]
    plan = _plan(lights)
    st = _settings(shadow_bias=0.25, pcf_spacing=1.5)
    data = build_frame_data(lights, _camera(), (0.1, 0.2, 0.3), st, plan, LitInputs(atlas=AtlasShape(256, 3)))
    F, L = programs.FRAME_STRUCT, programs.LIGHT_STRUCT
    assert F.unpack(data.frame, 0, "light_count") == 4
    assert F.unpack(data.frame, 0, "tile_size") == 256 and F.unpack(data.frame, 0, "atlas_columns") == 3
    assert F.unpack(data.frame, 0, "constant_bias") == pytest.approx(0.25)
    assert F.unpack(data.frame, 0, "pcf_spacing") == pytest.approx(1.5)
    np.testing.assert_allclose(F.unpack(data.frame, 0, "world_color"), (0.1, 0.2, 0.3), rtol=1e-6)
    np.testing.assert_allclose(F.unpack(data.frame, 0, "view_proj"), _camera().projection @ _camera().view, rtol=1e-6)

    modes = [L.unpack(data.lights, i, "shadow_mode") for i in range(4)]
    assert modes == [0, 1, 0, -1]  # SINGLE, CUBE, SINGLE, NONE
    cube = plan.lights[1].tiles
    np.testing.assert_array_equal(L.unpack(data.lights, 1, "tiles"), cube[:4])
    np.testing.assert_array_equal(L.unpack(data.lights, 1, "tiles_45"), cube[4:6])
    np.testing.assert_array_equal(L.unpack(data.lights, 3, "tiles"), [-1, -1, -1, -1])
    assert L.unpack(data.lights, 0, "sun_tan_half_angle") == pytest.approx(math.tan(math.radians(5)))
    assert L.unpack(data.lights, 2, "spot_cos_half") == pytest.approx(math.cos(math.radians(30)))
    assert L.unpack(data.lights, 0, "spot_cos_half") == pytest.approx(-2.0)  # not a spot: no cone
    # Every planned tile is packed with its own fit; the rest of the block is zero.
    T = programs.TILE_STRUCT
    for i, tile in enumerate(plan.tiles):
        assert T.unpack(data.tiles, i, "near") == pytest.approx(tile.fit.near, rel=1e-6)
        assert T.unpack(data.tiles, i, "far") == pytest.approx(tile.fit.far, rel=1e-6)
    assert not data.tiles[len(plan.tiles) :].any()


@pytest.mark.parametrize("kernel", [1, 3, 5, 15])
def test_pcf_weights_compile_in_as_the_separable_factor_of_the_normalised_kernel(kernel):
    lights = [_light("SUN")]
    data = build_frame_data(lights, _camera(), (0, 0, 0), _settings(pcf_kernel_size=kernel), _plan(lights))
    radius = data.defines["PCF_RADIUS"]
    assert radius == kernel // 2
    weights = np.array([float(w) for w in data.defines["PCF_WEIGHTS_LIST"].split(",")])
    assert len(weights) == 2 * radius + 1
    full = kernels.pcf_kernel(kernel)
    np.testing.assert_allclose(np.outer(weights, weights).ravel(), full[:, 2], rtol=1e-7)
    assert np.outer(weights, weights).sum() == pytest.approx(1.0, abs=1e-6)


def test_lights_with_maps_come_first_and_only_they_run_the_filter_loop():
    sun, lamp, spot = _light("SUN"), _light("POINT", use_shadow=False), _light("SPOT")
    lights = [lamp, sun, spot]
    plan = shadows.ShadowPlan()
    plan.lights = {1: shadows.LightShadow("SINGLE", [0]), 2: shadows.LightShadow("SINGLE", [1])}
    data = build_frame_data(lights, _camera(), (0, 0, 0), _settings(), plan)
    assert data.order == [1, 2, 0]
    F, L = programs.FRAME_STRUCT, programs.LIGHT_STRUCT
    assert F.unpack(data.frame, 0, "shadowed_count") == 2 and F.unpack(data.frame, 0, "light_count") == 3
    modes = [L.unpack(data.lights, i, "shadow_mode") for i in range(3)]
    assert modes == [SHADOW_MODE.value("SINGLE")] * 2 + [SHADOW_MODE.value("NONE")]
    assert L.unpack(data.lights, 0, "type") == LIGHT_TYPE.value("SUN")
    assert L.unpack(data.lights, 2, "type") == LIGHT_TYPE.value("POINT")


def test_only_what_a_filter_reads_varies_its_shader_variant():
    def defines(**kw):
        lights = [_light("SUN")]
        return build_frame_data(lights, _camera(), (0, 0, 0), _settings(**kw), _plan(lights)).defines

    assert defines(shadow_filter="NONE", pcf_kernel_size=3) == defines(shadow_filter="NONE", pcf_kernel_size=9)
    assert defines(shadow_filter="NONE", shadow_samples=64) == defines(shadow_filter="NONE", shadow_samples=8)
    assert defines(shadow_filter="PCF", shadow_early_out=False) == defines(shadow_filter="PCF")
    assert defines(shadow_filter="JITTER", shadow_samples=20)["DISK_SAMPLES"] == 16  # whole rings of 8
    assert defines(shadow_filter="PCSS", shadow_early_out=False)["EARLY_OUT"] is False
    assert defines(shadow_filter="PCSS")["SHADOW_FILTER"] == "FILTER_PCSS"


def test_more_lights_than_the_block_holds_is_an_error_not_a_silent_drop():
    lights = [_light("POINT", use_shadow=False)] * (programs.MAX_LIGHTS + 1)
    with pytest.raises(ValueError, match="at most"):
        build_frame_data(lights, _camera(), (0, 0, 0), _settings(), shadows.ShadowPlan())


# Which struct each GLSL variable name holds in the scene shaders.
_VARIABLES = {"frame": programs.FRAME_STRUCT, "L": programs.LIGHT_STRUCT, "T": programs.TILE_STRUCT,
              "tile": programs.TILE_STRUCT}  # fmt: skip


def test_scene_shaders_read_only_fields_their_structs_declare():
    entries = ("lit.frag.glsl", "lit_settle.frag.glsl", "lit_debug.frag.glsl")
    stages = entries + ("mesh.vert.glsl", "shadow_depth.vert.glsl", "shadow_depth.frag.glsl")
    sources = [ROOT / "shaders" / p for p in stages]
    sources += sorted((ROOT / "shaders" / "lib").glob("*.glsl"))
    used = 0
    for path in sources:
        text = re.sub(r"/\*.*?\*/", "", path.read_text(), flags=re.S)
        for var, field in re.findall(r"\b(frame|L|T|tile)\.([A-Za-z_]\w*)", text):
            assert field in _VARIABLES[var].layout, f"{path.name}: {var}.{field} is not a {_VARIABLES[var].name} field"
            used += 1
    assert used > 30


def test_a_frame_without_maps_compiles_no_shadow_filter():
    """Lights without maps cost nothing extra: every filter setting gives the one variant with
    no filter code when no light has a map (and so one compile, not one per filter)."""
    lights = [_light("POINT", use_shadow=False), _light("SUN", use_shadow=False)]
    variants = {
        tuple(
            sorted(
                build_frame_data(
                    lights, _camera(), (0, 0, 0), _settings(shadow_filter=f), _plan(lights)
                ).defines.items()
            )
        )
        for f in ("NONE", "HARDWARE", "PCF", "JITTER", "PCSS")
    }
    assert len(variants) == 1
    assert dict(next(iter(variants)))["SHADOW_FILTER"] == "FILTER_NONE"
    shadowed = [_light("SUN")]
    assert build_frame_data(shadowed, _camera(), (0, 0, 0), _settings(), _plan(shadowed)).defines["SHADOW_FILTER"] == (
        "FILTER_PCF"
    )


def test_an_area_light_plans_no_map_for_the_face_behind_it():
    """Casters above and below a light 4 m up that points down: a point light needs the +Z
    face for the box above it, an area light (which lights only the half-space in front of
    it) does not; a tilted area light keeps every face its front half-space reaches."""
    below = lightspace.box_corners(np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, 1.0]))
    above = lightspace.box_corners(np.array([-1.0, -1.0, 6.0]), np.array([1.0, 1.0, 7.0]))
    corners = np.stack([below, above])
    down = np.eye(4)
    down[:3, 3] = (0.0, 0.0, 4.0)  # lights look along local -Z: straight down
    point = Light(type="POINT", color=np.ones(3), matrix=down, radius=0.1)
    area = Light(type="AREA", color=np.ones(3), matrix=down, radius=0.0, size=1.0, size_x=1.0, size_y=1.0)
    point_faces = shadows.plan_shadows([point], corners, shadows.MapOptions(64)).lights[0].tiles
    area_faces = shadows.plan_shadows([area], corners, shadows.MapOptions(64)).lights[0].tiles
    plus_z = 4  # CUBE_FORWARDS order: +X, -X, +Y, -Y, +Z, -Z
    assert np.allclose(lightspace.CUBE_FORWARDS[plus_z], (0, 0, 1))
    assert point_faces[plus_z] >= 0 and area_faces[plus_z] == -1
    assert sum(t >= 0 for t in area_faces) == sum(t >= 0 for t in point_faces) - 1
    tilted = down.copy()
    tilted[:3, :3] = lightspace.look_at((0, 0, 0), (1.0, 0.0, 0.2))[:3, :3].T  # faces +X, a bit up
    area_tilted = Light(type="AREA", color=np.ones(3), matrix=tilted, radius=0.0, size=1.0, size_x=1.0, size_y=1.0)
    assert shadows.behind_area_light(lightspace.CUBE_FORWARDS[1], area_tilted.direction)  # -X is behind
    assert not shadows.behind_area_light(lightspace.CUBE_FORWARDS[plus_z], area_tilted.direction)


def _finite_plan(plan):
    for t in plan.tiles:
        for m in (t.fit.view, t.fit.proj):
            assert np.all(np.isfinite(m))
        assert t.fit.far > t.fit.near and np.isfinite(t.fit.far)
        assert t.fit.texel > 0 or t.fit.texel_per_distance > 0


@pytest.mark.parametrize(
    "case",
    [
        "light_on_the_ground_plane",
        "light_inside_the_caster",
        "camera_inside_the_caster",
        "nothing_in_view",
        "tiny",
        "huge",
    ],
)
def test_cropped_plans_stay_finite_at_degenerate_and_extreme_inputs(case):
    """The crops' maths (receivers cut to the view, flat-caster tests, off-centre windows) at
    the inputs where a division or a projection could break: every planned map has finite
    matrices and a positive depth range and texel, and each case plans what it should."""
    ground = lightspace.box_corners(np.array([-50.0, -50.0, 0.0]), np.array([50.0, 50.0, 0.0]))
    caster = lightspace.box_corners(np.array([-0.5, -0.5, 0.0]), np.array([0.5, 0.5, 1.0]))
    scale, eye, target, light_at = 1.0, (0.0, -6.0, 3.0), (0.0, 1.0, -0.5), (1.0, 1.0, 4.0)
    if case == "light_on_the_ground_plane":
        light_at = (3.0, 0.0, 0.0)
    elif case == "light_inside_the_caster":
        light_at = (0.0, 0.0, 0.5)
    elif case == "camera_inside_the_caster":
        eye = (0.0, 0.0, 0.5)
    elif case == "nothing_in_view":
        target = (0.0, -1.0, 0.2)  # looking away, over the ground's far edge... at the sky
        eye = (0.0, -60.0, 3.0)
    elif case in ("tiny", "huge"):
        scale = 1e-4 if case == "tiny" else 1e6

    def plan_at(scale, pcss):
        corners = np.stack([ground, caster]) * scale
        view = lightspace.look_at(np.array(eye) * scale, target)
        projection = lightspace.perspective(math.radians(50), 16 / 9, 0.1 * scale, 1000.0 * scale)
        camera = Camera(view=view, projection=projection)
        view_corners = lightspace.frustum_corners(camera.projection @ camera.view)
        lights = [
            _light("SUN", angle=math.radians(2)),
            _light("SPOT", position=np.array(light_at) * scale, spot_size=math.radians(120)),
            _light("POINT", position=np.array(light_at) * scale),
            _light("AREA", position=np.array(light_at) * scale, size=1.0 * scale, size_x=scale, size_y=scale),
        ]
        for light in lights:
            light.radius *= scale  # the light's size scales with the scene
        return shadows.plan_shadows(
            lights, corners, shadows.MapOptions(512, pcss=pcss), shadows.ViewFit(view_corners, camera)
        )

    for pcss in (False, True):
        plan = plan_at(scale, pcss)
        _finite_plan(plan)
        if case == "nothing_in_view":
            assert not plan.tiles  # nothing the camera sees can be shadowed
        elif case in ("tiny", "huge"):
            # Scale changes nothing but the sizes: the same maps, texels scaled with the scene
            # (to within one 2^(1/4) step of the extent quantisation, whose grid is absolute).
            unit = plan_at(1.0, pcss)
            assert [(e.mode, e.tiles) for e in plan.lights.values()] == [
                (e.mode, e.tiles) for e in unit.lights.values()
            ]
            for a, b in zip(plan.tiles, unit.tiles, strict=True):
                assert a.fit.texel == pytest.approx(b.fit.texel * scale, rel=0.19)
                assert a.fit.texel_per_distance == pytest.approx(b.fit.texel_per_distance, rel=0.19)


def test_every_uniform_block_fits_what_any_gl_allows():
    """GL guarantees 16 KiB per uniform block (GL_MAX_UNIFORM_BLOCK_SIZE): the lights table and
    the shadow-tile table, at their maximum counts, stay within it."""
    for program in (programs.LIT, shadow_programs.SHADOW_DEPTH):
        for struct, name, count in program.uniform_blocks:
            assert struct.stride * max(count, 1) <= 16384, (program.name, name)
    assert programs.MAX_SHADOW_TILES * programs.TILE_STRUCT.stride <= 16384


def test_flat_meshes_are_drawn_after_what_stands_on_them():
    """The lit pass draws nearest first so the depth test rejects hidden pixels before they are
    shaded; a ground's nearest point (under the camera) says nothing of what it hides, so
    flat boxes come after the others, each group nearest first."""
    from penumbra.engine.frame.draw_list import front_to_back

    camera = _camera()  # at (0, -6, 3)
    ground = lightspace.box_corners(np.array([-50.0, -50.0, 0.0]), np.array([50.0, 50.0, 0.0]))
    wall = lightspace.box_corners(np.array([-5.0, 20.0, 0.0]), np.array([5.0, 20.0, 4.0]))
    near = lightspace.box_corners(np.array([-0.5, -0.5, 0.0]), np.array([0.5, 0.5, 1.0]))
    far = lightspace.box_corners(np.array([-0.5, 9.5, 0.0]), np.array([0.5, 10.5, 1.0]))
    draws = [
        SimpleNamespace(name=n, corners=c)
        for n, c in (("ground", ground), ("far", far), ("wall", wall), ("near", near))
    ]
    assert [d.name for d in front_to_back(draws, camera)] == ["near", "far", "ground", "wall"]


def test_a_lit_variant_is_named_typed_and_every_field_reaches_the_defines():
    """``programs.LitVariant``: built by keyword only, each field checked (a wrong type or an
    unknown name raises, naming the field), and no field silently ignored: changing any one
    (where it applies) changes the program's defines."""
    LitVariant = programs.LitVariant
    with pytest.raises(TypeError):
        LitVariant("PCF")  # by position
    for field, bad in (
        ("debug", "yes"),
        ("world_lights", 1),
        ("disk_samples", True),
        ("shadow_filter", "PCF5"),
        ("specular_model", 2),
        ("depth_format", "FLOAT64"),
        ("light_counts", (1, 2)),
        ("pcf_weights", [1.0]),
        ("pcf_spacing", False),
    ):
        with pytest.raises(TypeError, match=field):
            LitVariant(**{field: bad})
    base = dict(shadow_filter="PCSS", pcf_weights=(1.0,), light_counts=(1, 2, 3))
    changed = {
        "shadow_filter": "PCF",
        "specular_model": "BLINN",
        "depth_format": "RGBA8",
        "disk_samples": 32,
        "early_out": False,
        "aux_outputs": False,
        "binned": True,
        "sampled": True,
        "light_counts": (0, 1, 1),
        "light_linking": True,
        "debug": True,
        "world_lights": True,
        "debug_term": 1,
    }
    # The PCF kernel and its spacing apply to the PCF filter only.
    pcf = dict(base, shadow_filter="PCF", pcf_weights=(0.25, 0.5, 0.25))
    cases = [(base, k, v) for k, v in changed.items()] + [
        (pcf, "pcf_weights", (0.1, 0.2, 0.4, 0.2, 0.1)),
        (pcf, "pcf_spacing", 2.0),
    ]
    fields = {f.name for f in dataclasses.fields(LitVariant)}
    assert {k for _, k, _ in cases} == fields, fields - {k for _, k, _ in cases}
    for start, key, value in cases:
        before = LitVariant(**start).defines()
        after = LitVariant(**{**start, key: value}).defines()
        assert before != after, f"LitVariant.{key} = {value!r} changes nothing"
    with pytest.raises(TypeError):
        programs.lit_defines("PCF")


def test_a_frames_first_plan_derives_every_sampled_light_of_finite_reach():
    """``ShadowPass.first_plan`` plans a multi-sample frame's lights for every sample at once:
    suns with an angle over their cone, spot, point and area lights over the scene grown by
    their reach; ``keep_sizes`` then keeps those lights' tiles for the samples to shear or
    move. A degenerate light (an area light of infinite size: no finite reach) is left to be
    planned every sample, and a one-sample frame grows nothing."""
    from penumbra.engine.frame.shadow_pass import ShadowPass

    ground = lightspace.box_corners(np.array([-5.0, -5.0, -0.1]), np.array([5.0, 5.0, 0.0]))
    caster = lightspace.box_corners(np.array([-0.5, -0.5, 0.5]), np.array([0.5, 0.5, 1.5]))
    draws = [SimpleNamespace(corners=ground), SimpleNamespace(corners=caster)]
    huge = _light("AREA", size=1.0, size_x=1.0, size_y=1.0)
    huge.matrix[0, 0] = np.inf
    lights = [_light("SPOT"), _light("POINT"), _light("SUN", angle=0.1), huge]
    shadows = ShadowPass()
    shadows.begin_frame()
    plan = shadows.first_plan(draws, lights, _camera(), _settings(), (64, 36), accumulate=True)
    shadows.keep_sizes(plan, _settings(), lights)
    derived = shadows.sizes[1]
    assert {0, 1, 2} <= set(plan.lights) and {0, 1, 2} <= set(derived)
    assert 3 not in derived
    assert shadows._reaches[0] == pytest.approx(0.25)
    one = ShadowPass()
    one.begin_frame()
    one.first_plan(draws, lights, _camera(), _settings(), (64, 36), accumulate=False)
    assert one._reaches is None
