"""The film's programs (``film.Film``): a sample added to the accumulation and the
accumulation resolved (by the total weight, or each pixel's with adaptive sampling), the
convergence check, and the nearest depth written where a pixel converged. A technique's own
film programs live in its module (``features/``)."""

from dataclasses import replace

from ...shaders.loader import Program, with_parts

# out = scale * src at (pixel - origin): a shadow tile from the scratch target into its place in
# the atlas (scale 1, origin the tile's corner; FLOAT16, RGBA8), a sample added to the
# accumulation (scale its weight, additive blending) and the accumulation resolved (scale
# 1 / total weight). The _SHADOW variant carries the Shadow pass along in a second target.
SCALED_COPY = Program(
    name="scaled_copy",
    vertex="fullscreen.vert.glsl",
    fragment="scaled_copy.frag.glsl",
    libs=("lib/film_gather.glsl", "lib/film_copies.glsl"),
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("IVEC2", "origin"), ("FLOAT", "scale")),
    samplers=(("FLOAT_2D", "src_color"),),
    outputs=(("VEC4", "out_color"),),
    defines=(("WITH_SHADOW", False),),
)
SCALED_COPY_SHADOW = replace(
    SCALED_COPY,
    name="scaled_copy_shadow",
    samplers=(("FLOAT_2D", "src_color"), ("FLOAT_2D", "src_shadow")),
    outputs=(("VEC4", "out_color"), ("VEC4", "out_shadow")),
    defines=(("WITH_SHADOW", True), ("CLAMP_SHADOW", False)),
)
# The accumulation resolved: the shadow's weighted mean of visibilities clamped to [0, 1]
# (rounding of the sums and of 1 / total weight may carry it past 1).
SCALED_RESOLVE_SHADOW = replace(
    SCALED_COPY_SHADOW, name="scaled_resolve_shadow", defines=(("WITH_SHADOW", True), ("CLAMP_SHADOW", True))
)


# Adaptive sampling (``film.Film``): a sample added only where the pixel has not converged
# (``converged`` > 0.5: nothing written), with the pixel's own weight in a further target;
# the accumulation resolved by each pixel's weight; the convergence check; and the nearest
# depth written where a pixel converged, so the lit pass does not shade it.
MASKED_COPY = Program(
    name="masked_copy",
    vertex="fullscreen.vert.glsl",
    fragment="masked_copy.frag.glsl",
    libs=("lib/film_gather.glsl", "lib/film_copies.glsl"),
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("FLOAT", "scale"),),
    samplers=(("FLOAT_2D", "src_color"), ("FLOAT_2D", "converged")),
    outputs=(("VEC4", "out_color"),),
    defines=(("WITH_SHADOW", False), ("WITH_WEIGHT", False)),
)
MASKED_COPY_WEIGHT = replace(
    MASKED_COPY,
    name="masked_copy_weight",
    outputs=(("VEC4", "out_color"), ("VEC4", "out_weight")),
    defines=(("WITH_SHADOW", False), ("WITH_WEIGHT", True)),
)
MASKED_COPY_SHADOW_WEIGHT = replace(
    MASKED_COPY,
    name="masked_copy_shadow_weight",
    samplers=MASKED_COPY.samplers + (("FLOAT_2D", "src_shadow"),),
    outputs=(("VEC4", "out_color"), ("VEC4", "out_shadow"), ("VEC4", "out_weight")),
    defines=(("WITH_SHADOW", True), ("WITH_WEIGHT", True)),
)
WEIGHTED_RESOLVE = Program(
    name="weighted_resolve",
    vertex="fullscreen.vert.glsl",
    fragment="weighted_resolve.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    samplers=(("FLOAT_2D", "src_color"), ("FLOAT_2D", "weight")),
    outputs=(("VEC4", "out_color"),),
    defines=(("WITH_SHADOW", False),),
)
WEIGHTED_RESOLVE_SHADOW = replace(
    WEIGHTED_RESOLVE,
    name="weighted_resolve_shadow",
    samplers=WEIGHTED_RESOLVE.samplers + (("FLOAT_2D", "src_shadow"),),
    outputs=(("VEC4", "out_color"), ("VEC4", "out_shadow")),
    defines=(("WITH_SHADOW", True),),
)
CONVERGENCE = Program(
    name="convergence",
    vertex="fullscreen.vert.glsl",
    fragment="convergence.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    # per_pixel > 0.5: pixels hold their own weights (``weight``), else all ``weight_sum``;
    # half_scale: what the every-other-sample accumulation is multiplied by (``Film._half_scale``).
    push_constants=(
        ("FLOAT", "threshold"),
        ("FLOAT", "weight_sum"),
        ("FLOAT", "per_pixel"),
        ("FLOAT", "half_scale"),
    ),
    samplers=(
        ("FLOAT_2D", "accum"),
        ("FLOAT_2D", "half_accum"),
        ("FLOAT_2D", "converged"),
        ("FLOAT_2D", "weight"),
    ),
    outputs=(("VEC4", "out_color"),),
)
CONVERGENCE = replace(CONVERGENCE, defines=(("ERROR_OUTPUT", False),))
# The NOISE debug view: each pixel's error estimate as the check reads it (``Film.error_array``).
CONVERGENCE_ERROR = replace(CONVERGENCE, name="convergence_error", defines=(("ERROR_OUTPUT", True),))


def convergence_program(error_output=False, parts=()):
    """The convergence check (or, ``error_output``, its estimate for the NOISE view), with the
    frame's techniques' ``parts`` of it (``FilmPart.convergence``: the world ratio's, so the
    means it compares take the world's light through its ratio)."""
    return with_parts(CONVERGENCE_ERROR if error_output else CONVERGENCE, *parts)


CONVERGED_DEPTH = Program(
    name="converged_depth",
    vertex="fullscreen.vert.glsl",
    fragment="converged_depth.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("INT", "reach"),),  # the gathering film's reach (0: none)
    samplers=(("FLOAT_2D", "converged"),),
    outputs=(("VEC4", "out_color"),),
    depth_write="ANY",
)


# The gathering film (``sampling.gathers``): a copy program whose source is gathered from the
# sample pixels within the filter's reach (``lib/film_gather.glsl``), for adding a sample to
# the accumulations; the window's weights along x and y (made in Python) as push constants,
# its reach compiled in.
GATHER_PUSH = (("MAT3", "gather_wx"), ("MAT3", "gather_wy"))


# Blender's gpu module binds at most this many colour targets to a framebuffer.
MAX_TARGETS = 6


def with_copies(program, count):
    """``program`` (SCALED_COPY, MASKED_COPY or a variant of theirs) adding ``count`` further
    sources (``src_copy0`` ..) times its scale into as many further targets (``out_copy0`` ..)
    in the same pass (lib/film_copies.glsl): a sample's accumulations in as few passes as
    Blender's six colour targets allow (``film.Film.accumulate``)."""
    count = int(count)
    if count <= 0:
        return program
    if len(program.outputs) + count > MAX_TARGETS:
        raise ValueError(f"{program.name}: {len(program.outputs)} targets and {count} copies exceed {MAX_TARGETS}")
    return replace(
        program,
        name=f"{program.name}_copies{count}",
        samplers=program.samplers + tuple(("FLOAT_2D", f"src_copy{k}") for k in range(count)),
        outputs=program.outputs + tuple(("VEC4", f"out_copy{k}") for k in range(count)),
        defines=program.defines + (("EXTRA_COPIES", count),),
    )


def gathering(program, reach):
    """``program`` (SCALED_COPY, MASKED_COPY or a variant of theirs) gathering its source
    from the sample pixels ``reach`` each way (``sampling.gather_reach``, compiled in)."""
    return replace(
        program,
        name=f"{program.name}_gather{int(reach)}",
        push_constants=program.push_constants + GATHER_PUSH,
        defines=program.defines + (("GATHER", True), ("GATHER_REACH", int(reach))),
    )
