"""The frame's shadow pass: plan the maps the lights need (``shadows.planning``, numpy only),
apply shadow linking to each map's casters, and draw the maps whose content changed into the
atlas (``shadow_maps.ShadowAtlas``)."""

import dataclasses
import math

import numpy as np

from ..enums import DEPTH_FORMAT
from ..scene import simplify
from ..scene.materials import Material
from ..shadows import light_bins, lightspace
from ..shadows.planning import (
    MAX_SHADOW_TILES,
    Density,
    FrameShare,
    MapOptions,
    ShadowPlan,
    ViewFit,
    cascade_slices,
    frame_sizes,
    frame_tiles,
    plan_shadows,
)
from . import sampling
from .draw_list import corners_of
from .programs import RSM_TEXEL_BYTES, image_premultiplied_bits
from .shadow_maps import Caster, ShadowAtlas, TreeCutout

UNSET = object()  # ``ShadowPass.depth_range`` before this frame's first plan
_DEFAULT_MATERIAL = Material()  # the albedo of a caster without material parts (reflective maps)


class ShadowPass:
    def __init__(self, pool=None):
        self.atlas = ShadowAtlas(pool)
        self.depth_range = UNSET  # the frame's visible depth range, once a plan computed it
        self._receivers = None  # and what the camera sees (lightspace.visible_receivers)
        self._sun_parts = None  # and the boxes' parts in its frustum (lightspace.view_parts)
        self._casters = (None, None, False)  # (the frame's draw list, what each draw casts, rsm): once a frame
        self._sizes = None  # {light index: map sizes} of the frame's first plan (``keep_sizes``)
        self._hints = None  # {light index: map sizes} a navigation frame keeps where close (``hint_sizes``)
        self.windows = None  # the cropped maps' windows while the view moves (``begin_frame``)
        self._derived = None  # {light index: (mode, tiles, position)}: what later samples shear or move
        self._reaches = None  # {light index: reach} the frame's first plan grew the scene by
        self.reach = 0.0  # pixels the frame's samples look beyond the image (the pixel filter)
        self.reflective = False  # the maps hold what each light sees too (features/bounce.py)
        self.receivers = None  # boxes beyond the draws that take light (``begin_frame``)
        self._shared = None  # (draws, key, what the frame's plans through one camera share): ``_frame_view``

    def begin_frame(self, reach=0.0, reflective=False, receivers=None, navigating=False):
        """Forget the last frame's camera-dependent bounds, casters and map sizes. ``reach``:
        how many pixels beyond the image the frame's samples look (the pixel filter's reach in
        a multi-sample frame; 0 for one sample), so maps are planned for all of them;
        ``reflective``: the maps are reflective shadow maps (``FramePlan.reflective``);
        ``receivers``: boxes beyond the draws that take light (``FramePlan.receivers``: the
        media), which the maps cover as they cover the surfaces the camera sees.
        ``navigating``: a frame while the view moves, whose cropped maps keep the windows of
        the navigation frames before it while those hold what it needs (``ViewFit.windows``);
        any other frame forgets them."""
        self.windows = self.windows if navigating else None
        if navigating and self.windows is None:
            self.windows = {}
        self.reflective = bool(reflective)
        self.receivers = None if receivers is None or not len(receivers) else np.asarray(receivers, np.float64)
        self.depth_range = UNSET
        self.atlas.growing = False  # the frame's first maps size the atlas afresh
        self._receivers = None
        self._sun_parts = None
        self._shared = None
        self._casters = (None, None, False)
        self._sizes = None
        self._hints = None
        self._derived = None
        self.reach = float(reach)

    def keep_sizes(self, plan, settings, lights):
        """The frame's later samples draw each light's maps at the sizes of ``plan`` (the
        frame's plan with every light at its centre, ``first_plan``): planned once a sample,
        not twice; and its lights' maps sheared to each sample's direction (suns) or moved to
        its point of the light (the others), not fitted again."""
        self._sizes = frame_sizes(plan, max(1, int(settings.shadow_map_size)))
        self._derived = frame_tiles(plan, lights, self._reaches)

    @property
    def sizes(self):
        """The frame's map sizes and derived suns (``keep_sizes``), or None."""
        return None if self._sizes is None else (self._sizes, self._derived)

    def hint_sizes(self, sizes):
        """A navigation frame that plans afresh: each light keeps ``sizes`` (the last planning
        navigation frame's) where density asks for sizes close to them (``FrameShare``)."""
        self._hints = sizes

    def use_sizes(self, sizes):
        """A later call of the same frame: what its first call kept (``sizes``: the property's
        value, or a navigation frame's map sizes alone)."""
        if isinstance(sizes, tuple):
            self._sizes, self._derived = sizes
        else:
            self._sizes, self._derived = sizes, None

    def first_plan(self, draws, lights, camera, settings, size, accumulate):
        """The frame's plan with every light at its centre. In a frame of several samples a sun
        with an angle is fitted to hold every direction its samples take (``FrameShare``'
        ``cones``), so each sample shears this plan's maps instead of fitting its own."""
        cones = reaches = None
        if accumulate:
            cones = {
                i: math.tan(0.5 * min(max(lt.angle, 0.0), math.pi * 0.99))
                for i, lt in enumerate(lights)
                if lt.type == "SUN" and not lt.world and lt.angle > 0.0
            }
            # Spot, point and area lights: planned over everything grown by how far their
            # samples move them, so each sample moves the map's eye instead of planning one.
            # (A light whose reach is not finite, a degenerate one, is planned every sample.)
            reaches = {
                i: light_bins.light_reach(lt) for i, lt in enumerate(lights) if lt.type != "SUN" and not lt.world
            }
            reaches = {i: r for i, r in reaches.items() if math.isfinite(r)}
        self._reaches = reaches
        return self.plan(draws, lights, camera, settings, size, spread=(cones, reaches))

    def plan(self, draws, lights, camera, settings, size, map_size=None, known=None, spread=None):
        """The shadow plan of ``lights`` (numpy only, nothing drawn) for a frame of ``size``
        (width, height), with maps of ``map_size`` (default: the setting). ``known``: (map
        sizes, derived maps) the frame's first plan kept (``sizes``); ``spread``: (sun cones,
        reaches) a first plan is fitted over (``first_plan``). With reflective maps (the
        bounce, ``begin_frame``) maps hold every visible surface the light reaches, not only
        those a caster can shadow (``MapOptions.reflective``)."""
        sizes, derived = known if known is not None else (None, None)
        cones, reaches = spread if spread is not None else (None, None)
        corners, seen, camera, size, view_corners, flat = self._frame_view(draws, camera, settings, size)
        map_size = max(1, int(settings.shadow_map_size)) if map_size is None else map_size
        if self.depth_range is UNSET:
            # The visible depth range and the visible receivers depend only on the unjittered
            # camera and the instances' bounds: once per frame, not per sample.
            self.depth_range = lightspace.view_depth_range(camera.projection, camera.view, seen, camera.is_ortho)
            self._receivers = lightspace.visible_receivers(seen, camera.projection @ camera.view)
        if view_corners is not None and self._sun_parts is None:
            # Every sun fitted to the whole view (the world's directions too) fits to these.
            self._sun_parts = lightspace.view_parts(seen, view_corners)
        options = MapOptions(
            map_size,
            int(settings.shadow_cascades),
            kernel=fixed_kernel(settings),
            pcss=settings.shadow_filter == "PCSS",
            world_map_size=getattr(settings, "world_map_size", None),
            reflective=self.reflective,
        )
        shared = self._shared[2]
        if shared["slices"] is None:
            shared["slices"] = cascade_slices(
                seen, view_corners, camera, int(settings.shadow_cascades), self.depth_range
            )
        fit = ViewFit(
            view_corners,
            camera,
            self.depth_range,
            receivers=self._receivers,
            density=_density(camera, settings, size),
            sun_parts=self._sun_parts,
            extra=self.receivers,
            windows=self.windows,
            flat=flat,
            slices=shared["slices"],
        )
        share = FrameShare(known_sizes=sizes, hinted_sizes=self._hints, cones=cones, reaches=reaches, derived=derived)
        return plan_shadows(lights, corners, options, fit, share)

    def _frame_view(self, draws, camera, settings, size):
        """What every plan of a frame through ``camera`` shares, made once a frame (its
        samples plan through one unjittered camera, and one draw list, unless the view moves
        between them: depth of field, motion blur): the draws' boxes, those and the receivers
        beyond them (the media), the camera widened by the frame's reach and the size it
        covers then, its frustum's corners (suns fitted to the view), the boxes' flat-caster
        test (``lightspace.FlatCasters``), and a dict of the rest (the sun's cascade slices)."""
        key = (
            camera.projection.tobytes(),
            camera.view.tobytes(),
            bool(camera.is_ortho),
            None if size is None else tuple(size),
            settings.shadow_sun_fit,
            int(settings.shadow_cascades),
            self.reach,
        )
        shared = self._shared
        if shared is not None and shared[0] is draws and shared[1] == key:
            return shared[3]
        corners = corners_of(draws)
        # What takes light: the draws' boxes and the receivers beyond them (the media).
        seen = corners if self.receivers is None else np.concatenate([corners, self.receivers])
        if self.reach > 0.0 and size is not None:
            projection, size = sampling.widened_projection(camera.projection, self.reach, *size)
            camera = dataclasses.replace(camera, projection=projection)
        view_corners = _view_corners(camera) if settings.shadow_sun_fit == "VIEW" else None
        value = (corners, seen, camera, size, view_corners, lightspace.FlatCasters(corners))
        self._shared = (draws, key, {"slices": None}, value)
        return value

    def draw(self, frame, sample):
        """Plan the maps ``sample`` (``renderer.Sample``: its draws and lights, planned from its
        unjittered camera) of ``frame`` (``renderer.FramePlan``) needs (numpy) and draw the
        ones whose content changed: a batch of one (``plan_sample``, ``draw_batch``). Returns
        the plan (also ``sample.plan``)."""
        sample.plan = self.plan_sample(frame, sample)
        self.draw_batch(frame, [sample])
        return sample.plan

    def plan_sample(self, frame, sample):
        """The maps ``sample`` needs (numpy, nothing drawn): planned at the frame's sizes (or
        clamped where the GPU's largest texture or the bounce's budget asks), shifted by the
        sample's map jitter, with shadow linking's casters. Returns the plan."""
        draws, lights, camera, stats = sample.draws, sample.lights, sample.camera, sample.stats
        settings, size = frame.settings, frame.size
        map_size = max(1, int(settings.shadow_map_size))
        plan = self.plan(draws, lights, camera, settings, size, map_size, (self._sizes, self._derived))
        if not plan.tiles:
            return plan
        columns, _rows = self.atlas.grid(len(plan.tiles))
        clamped = min(map_size, _gpu_texture_limit() // columns)
        if max(t.size for t in plan.tiles) > clamped:
            stats.messages.append(
                f"Penumbra: shadow map size {map_size} clamped to {clamped}: {len(plan.tiles)} maps share this "
                "GPU's largest texture"
            )
            map_size = clamped
            self._sizes = self._derived = None  # planned afresh at the clamped size
            plan = self.plan(draws, lights, camera, settings, size, map_size)
        rsm = self.reflective
        if rsm:  # the bounce's reflective targets, budgeted before they are allocated
            fitted = reflective_map_size(len(plan.tiles), max(t.size for t in plan.tiles))
            if fitted is not None:
                stats.messages.append(
                    f"Penumbra: shadow map size {map_size} reduced to {fitted} for the bounce's reflective maps: "
                    f"{len(plan.tiles)} maps would take more than {RSM_BUDGET_BYTES >> 20} MB"
                )
                map_size = fitted
                self._sizes = self._derived = None
                plan = self.plan(draws, lights, camera, settings, size, map_size)
        if plan.unshadowed:
            stats.messages.append(
                f"Penumbra: {plan.unshadowed} light(s) left unshadowed: more than {MAX_SHADOW_TILES} shadow maps"
            )
        for i, entry in plan.lights.items():  # this sample's sub-texel shift of the light's maps
            shift = lights[i].map_jitter
            if shift[0] or shift[1]:
                for t in entry.tiles:
                    if t >= 0:
                        tile = plan.tiles[t]
                        tile.fit = lightspace.shifted(tile.fit, shift, tile.size)
        for i, entry in plan.lights.items():  # shadow linking: only the light's blockers cast
            blockers = lights[i].blockers
            if blockers is not None:
                for t in entry.tiles:
                    if t >= 0:
                        tile = plan.tiles[t]
                        tile.casters = np.array(
                            [c for c in tile.casters if blockers.links(draws[c].instance.names)], dtype=np.int64
                        )
        return plan

    def casters(self, draws, caches):
        """What each of the frame's ``draws`` casts (``caster``): made once a frame (motion
        blur gives each sample its draws, and its casters)."""
        rsm = self.reflective
        if self._casters[0] is not draws or self._casters[2] != rsm:
            self._casters = (draws, [caster(d, caches.materials, caches.textures, rsm) for d in draws], rsm)
        return self._casters[1]

    def batches(self, frame, samples):
        """``samples`` (planned, in order, sharing one draw list) in groups whose maps are drawn
        together (``draw_batch``): a group's maps are the union of its samples' (a map two
        samples plan alike, a light that does not move, is drawn once), at most
        MAX_SHADOW_TILES, in an atlas no wider than the GPU's largest texture and of at most
        MAP_BATCH_BYTES (a sample whose maps alone take more is a group of its own)."""
        limit = _gpu_texture_limit()
        texel = DEPTH_FORMAT[frame.settings.shadow_depth_format].bytes + (RSM_TEXEL_BYTES if self.reflective else 0)
        casters = self.casters(samples[0].draws, frame.caches)
        groups, group, keys, sizes = [], [], set(), []
        for sample in samples:
            plan = sample.plan
            tiles = plan.tiles if plan is not None else []
            new = {}
            for tile in tiles:
                new.setdefault(_content(tile, casters, sample.alpha_offset), tile.size)
            added = [n for k, n in new.items() if k not in keys]
            if group and not _fits(sizes + added, texel, limit):
                groups.append(group)
                group, keys, sizes = [], set(), list(new.values())
            else:
                sizes += added
            group.append(sample)
            keys.update(new)
        groups.append(group)
        return groups

    def draw_batch(self, frame, samples):
        """Draw the maps of ``samples`` (a group of ``batches``) whose content changed: the
        union of their plans placed in the atlas at once (each sample's tiles get their place),
        every opaque caster batch drawn once for all of them (``ShadowAtlas.render``: instanced,
        whatever the number of maps and samples). The frame's ``GpuCaches`` serve alpha
        cutouts (material blocks, images) and the casters' levels of detail in each map."""
        settings, caches = frame.settings, frame.caches
        planned = [s for s in samples if s.plan is not None and s.plan.tiles]
        if not planned:
            return
        stats = planned[0].stats
        draws = planned[0].draws
        casters = self.casters(draws, caches)
        rsm = self.reflective
        # Reflective maps draw each caster per material (its albedo): whole, not simplified.
        detail = 0.0 if rsm else float(getattr(settings, "shadow_caster_detail", 0.0))
        tiles, alphas, levels, where, twins = [], [], {}, {}, []
        for sample in planned:
            plan = sample.plan
            assert sample.draws is draws, "a batch's samples share one draw list"
            at = map_levels(plan, draws, casters, caches.batches, detail)
            for t, tile in enumerate(plan.tiles):
                key = _content(tile, casters, sample.alpha_offset)
                index = where.get(key)
                if index is None:
                    index = where[key] = len(tiles)
                    tiles.append(tile)
                    alphas.append(sample.alpha_offset)
                    levels.update({(index, c): lod for (u, c), lod in at.items() if u == t})
                twins.append((tile, index))
        # A map two samples share is drawn once: the others reuse it, as a later frame would.
        stats.shadow_maps_reused += len(twins) - len(tiles)
        union = ShadowPlan(tiles=tiles)
        self.atlas.place(union, settings.shadow_depth_format, rsm)
        self.atlas.growing = True
        for tile, index in twins:
            tile.origin = tiles[index].origin
        if self.atlas.rsm_refused:
            stats.messages.append(
                f"Penumbra: this GPU refused the bounce's reflective maps ({self.atlas.rsm_refused}): "
                "rendered without the bounce"
            )
        self.atlas.render(
            union, casters, caches.shaders, settings.shadow_cull_front, stats, alphas, frame.origin, levels
        )


# The atlas of a batch of samples' maps (``ShadowPass.batches``) takes at most this many bytes;
# a sample whose own maps take more draws them alone (its frame's sizes decided them).
MAP_BATCH_BYTES = 256 << 20


def _content(tile, casters, alpha_offset):
    """What a planned map holds, wherever it is placed: two samples' maps with the same are
    one map. Alpha cut-outs cover other texels in each sample (``alpha_offset``)."""
    fit = tile.fit
    cutouts = any(casters[c] is not None and casters[c].cutouts for c in tile.casters)
    return (
        fit.view_proj.tobytes(),
        fit.near,
        fit.far,
        tile.size,
        np.asarray(tile.casters, np.int64).tobytes(),
        alpha_offset if cutouts else None,
    )


def _fits(sizes, texel, limit):
    """Whether maps of ``sizes`` fit one atlas (``ShadowAtlas.grid`` of slots as wide as the
    widest, filled by area: ``pack_tiles`` leaves no gap between power-of-two maps) of at
    most MAP_BATCH_BYTES (``texel`` bytes a texel), at most ``limit`` texels wide and at most
    MAX_SHADOW_TILES maps."""
    if len(sizes) > MAX_SHADOW_TILES:
        return False
    slot = max(sizes, default=1)
    # A slot for each map at most; by area, as many as the maps fill.
    count = min(len(sizes), math.ceil(sum(n * n for n in sizes) / (slot * slot)))
    columns, rows = ShadowAtlas.grid(count)
    return columns * slot <= limit and rows * slot <= limit and columns * rows * slot * slot * texel <= MAP_BATCH_BYTES


def caster(d, materials, textures, rsm=False):
    """What draw ``d`` draws into shadow maps (``shadow_maps.Caster``), or None when it casts
    no shadow (Ray Visibility > Shadow off). Parts with alpha cover each map texel in a
    fraction alpha of the samples (``shadow_maps.ShadowAtlas.render``). ``rsm``: reflective
    maps, whose opaque parts are drawn per material with its MaterialData (the albedo)."""
    if not d.instance.shadow:
        return None
    out = _caster(d, materials, textures)
    if rsm and out is not None and out.hair is None:
        whole = len(out.batches) == 1 and out.batches[0] is d.whole
        parts = [(b, d.material(i)) for i, b in d.parts if whole or any(b is x for x in out.batches)]
        if not parts:  # no material part: the default material's albedo
            parts = [(b, _DEFAULT_MATERIAL) for b in out.batches]
        out.rsm_parts = [(b, materials.get(m)) for b, m in parts]
        out.rsm_key = tuple((tuple(m.base_color), m.metallic) for _b, m in parts)
    return out


def _caster(d, materials, textures):
    if d.instance.hair is not None:  # hair strips: widened toward the light (``shadow_hair_program``)
        identity = (*d.identity, d.instance.hair)
        return Caster([d.whole], d.model, d.det, identity, triangles=d.triangles, hair=d.instance.hair)
    mats = [(index, batch, d.material(index)) for index, batch in d.parts]
    cull = bool(mats) and all(m.cull_shadow for _i, _b, m in mats)
    # Material > Settings > Transparent Shadows off: its alpha casts as an opaque surface.
    if not any(m.uses_alpha and m.transparent_shadow for _i, _b, m in mats):
        return Caster(
            [d.whole],
            d.model,
            d.det,
            d.identity,
            cull_back=cull,
            closed=d.closed,
            corners=d.corners,
            triangles=d.triangles,
        )
    solid, cutouts = [], []
    for _index, batch, mat in mats:
        if not (mat.uses_alpha and mat.transparent_shadow):
            solid.append(batch)
        elif mat.tree is not None and "FRAME" not in mat.tree.needs:
            cutouts.append((batch, materials.get(mat), None, tree_cutout(d, mat, materials, textures)))
        elif "alpha" in mat.textures:
            image = mat.textures["alpha"].image
            bits = image_premultiplied_bits(textures.premultiplied, [("alpha", image)])
            cutouts.append((batch, materials.get(mat), (textures.get(image), bits), None))
        elif mat.alpha > 0.0:
            cutouts.append((batch, materials.get(mat), None, None))
    identity = (*d.identity, tuple(id(m) for _i, _b, m in mats))
    return Caster(solid, d.model, d.det, identity, cutouts, cull_back=cull, triangles=d.triangles)


def tree_cutout(d, mat, materials, textures):
    """What a caster's compiled node tree needs in the depth pass (``shadow_maps.TreeCutout``)."""
    tree = mat.tree
    uniforms = d.tree_uniforms(tree)
    images = tuple(textures.get(ref.image) for ref in tree.images)
    if images:
        names = [ref.image for ref in tree.images]
        uniforms = {**uniforms, "image_premultiplied": image_premultiplied_bits(textures.premultiplied, (), names)}
    return TreeCutout(tree, materials.constants(mat), images, uniforms)


def map_levels(plan, draws, casters, batches, cell_texels):
    """Casters drawn into a map at that map's texel footprint: {(tile index, draw index):
    (batches, level, triangles)} for each opaque caster of at least ``simplify.MIN_TRIANGLES``
    triangles (drawn whole in the lit pass) whose clustering at cells of ``cell_texels`` map
    texels (at the caster's nearest depth in the map) keeps at most ``simplify.WORTH`` of its
    triangles. A cluster's vertex stays inside its cell, so the caster's outline in the map
    moves less than a cell's diagonal; the lit pass still draws every triangle. Empty when
    ``cell_texels`` is 0 (Caster Detail off)."""
    out = {}
    if not cell_texels > 0.0:
        return out
    for t, tile in enumerate(plan.tiles):
        fit = tile.fit
        for c in tile.casters:
            d, cast = draws[c], casters[c]
            geo = d.geometry
            if cast is None or cast.cutouts or geo is None or geo.triangle_count < simplify.MIN_TRIANGLES:
                continue
            if fit.orthographic:
                footprint, depth = (0.0, fit.texel), 1.0
            else:
                z = -(d.corners @ fit.view[2, :3] + fit.view[2, 3])  # depths along the light's view axis
                footprint, depth = (fit.texel_per_distance, 0.0), max(float(z.min()), fit.near)
            extent = float(np.max(geo.bounds[1] - geo.bounds[0]))
            stretch = float(np.linalg.svd(np.asarray(d.instance.matrix)[:3, :3], compute_uv=False)[0])
            level = simplify.level_for(extent, stretch, depth, footprint, cell_texels)
            lod = simplify.simplified(geo, level) if level is not None else None
            if lod is None:
                continue
            whole, _parts = batches.level((d.instance.key, geo.serial, level), lod)
            out[t, c] = ([whole], level, lod.triangle_count)
    return out


def _density(camera, settings, size):
    """How finely this frame's camera sees (``planning.Density``), or None when maps keep
    their full size (Texels per Pixel 0)."""
    per_pixel = float(settings.shadow_texels_per_pixel)
    if not per_pixel > 0.0 or size is None:
        return None
    per_depth, constant = lightspace.pixel_footprint(camera.projection, camera.is_ortho, *size)
    return Density(np.asarray(camera.view, dtype=np.float64), per_depth, constant, per_pixel)


def fixed_kernel(settings):
    """The radius in texels the scene's shadow filter reads around a lookup (not PCSS, whose
    kernel follows each light's size)."""
    kind = settings.shadow_filter
    if kind == "PCF":
        return (max(int(settings.pcf_kernel_size), 1) // 2) * max(float(settings.pcf_spacing), 0.0) + 1.0
    if kind == "JITTER":
        return max(float(settings.shadow_filter_radius), 0.0) + 1.0
    return 1.0


def _view_corners(camera):
    """The camera frustum's world corners, or None when its matrices are degenerate."""
    try:
        c = lightspace.frustum_corners(camera.projection @ camera.view)
    except np.linalg.LinAlgError:
        return None
    return c if np.all(np.isfinite(c)) else None


# The reflective targets of the bounce (two RGBA16F textures the atlas's size) take at most
# this many bytes: a frame whose maps would need more draws every map smaller (they share the
# depth pass's framebuffer, so the atlas's size is theirs), and says so.
RSM_BUDGET_BYTES = 1 << 30


def reflective_map_size(count, largest):
    """The largest map size at which ``count`` maps' reflective targets fit RSM_BUDGET_BYTES,
    or None when maps of ``largest`` texels already do (``ShadowAtlas.grid`` places them)."""
    columns, rows = ShadowAtlas.grid(max(1, count))
    per_texel = RSM_TEXEL_BYTES * columns * rows
    if largest * largest * per_texel <= RSM_BUDGET_BYTES:
        return None
    return max(1, int(math.isqrt(RSM_BUDGET_BYTES // per_texel)))


def _gpu_texture_limit():
    import gpu

    return gpu.capabilities.max_texture_size_get()
