"""The hooks a technique of the frame implements (``Feature``) and its part of a sample's lit
pass (``LitPart``); the registry is ``features/__init__.py``."""

import dataclasses
import weakref


@dataclasses.dataclass(frozen=True)
class LitPart:
    """A technique's part of one sample's lit pass: ``program``, its ``ProgramPart`` of the lit
    program (libraries, samplers, outputs and the defines that switch it on; None: it changes
    no program), ``blended`` the one blended surfaces take (None: ``program``'s); ``rows``,
    fields of the frame block (``programs.FRAME_STRUCT``) this technique sets; ``samplers``,
    {sampler name: texture} the lit program reads (bound with the frame's blocks); ``blocks``,
    {block name: packed std140 bytes} of uniform blocks its ``program`` declares; ``begin``:
    GPU work over the sample's frame block before the lit pass's draws
    (``begin(frame_block, stats)``), or None; ``between``: GPU work after the opaque surfaces
    are drawn and before the transmissive ones (``between(film, stats)``: what they see
    through), or None."""

    program: object = None
    blended: object = None
    rows: dict = dataclasses.field(default_factory=dict)
    samplers: dict = dataclasses.field(default_factory=dict)
    blocks: dict = dataclasses.field(default_factory=dict)
    begin: object = None
    between: object = None

    @property
    def blended_program(self):
        return self.blended if self.blended is not None else self.program


NO_PART = LitPart()


class Feature:
    """One technique of the frame. A renderer makes one of each registered technique
    (``Feature(renderer)``: the renderer's caches and pool, what GPU state it keeps between
    frames), and for each frame calls, where ``wanted(frame)`` said yes:

    * ``plan(frame)``: what it adds to the frame's plan (``renderer.FramePlan``), after the
      base plan (draw list, lights, the world's light) and before the samples;
    * ``film(frame)``: what it asks of the film, as keywords of ``Film.begin``, and
      ``film_part(frame)``: its own targets there (a ``film.FilmPart``; frames of several samples);
    * ``before_sample(frame, s)``: a stage of its own before sample ``s`` is set up; a frame
      sets up a batch of samples before it draws them, so a stage that needs the samples
      before ``s`` drawn says so (``starts_batch(frame, s)``: settling's test);
    * ``prepare(frame, sample)``: its change to the sample's view, scene or lights (``Sample``);
    * ``before_lit(frame, sample)``: GPU work the sample's lit pass reads (a depth prepass);
    * ``after_lit(frame, sample)``: GPU work over what the sample's lit pass left (its
      z-buffer), before the sample is accumulated: the passes' draws;
    * ``lit(frame, sample)``: its ``LitPart`` of the sample's lit pass, and ``capture(frame,
      sample)`` of a lit pass that captures the scene from elsewhere (``planar``, ``cubes``);
    * ``resolve(frame)``: after the last sample; ``memory_bytes(frame)``: what it holds.

    Every hook does nothing by default, so a technique implements only those it needs."""

    name = ""

    def __init__(self, renderer):
        # Held weakly: the renderer holds its techniques, and a cycle would leave the renderer
        # and its GPU objects to Python's cycle collector, freed whenever it runs, in whatever
        # GPU context is current then (``Renderer.close``).
        self._renderer = weakref.ref(renderer)

    @property
    def renderer(self):
        """The renderer this technique works for (None once it is gone)."""
        return self._renderer()

    def wanted(self, frame):
        """Whether ``frame`` needs this technique (its other hooks run only then)."""
        return False

    def plan(self, frame):
        pass

    def film(self, frame):
        return {}

    def film_part(self, frame):
        """Its targets in the film (a ``film.FilmPart``), or None."""
        return None

    def before_sample(self, frame, s):
        pass

    def starts_batch(self, frame, s):
        """Whether sample ``s`` must begin a batch (``Renderer._batch_end``): its
        ``before_sample`` needs the samples before it drawn (settling's test)."""
        return False

    def prepare(self, frame, sample):
        pass

    def before_lit(self, frame, sample):
        pass

    def after_lit(self, frame, sample):
        pass

    def lit(self, frame, sample):
        return NO_PART

    def capture(self, frame, sample):
        """Its ``LitPart`` of a lit pass that captures the scene from elsewhere (a Plane
        probe's mirrored view, a cube map's face: ``Renderer.capture``), or None: it takes no
        part there. Such a part changes what a surface shows and writes no target of the
        film's, nor reads the camera's own image."""
        return None

    def resolve(self, frame):
        pass

    def memory_bytes(self, frame):
        return 0

    def release(self):
        pass


def outputs_of(parts):
    """Colour targets ``parts`` (``ProgramPart``s, None for none) write besides the lit pass's
    colour: what a draw of the lit program again (``LitPass.draw_light``) must bind after it."""
    return sum(len(p.outputs) for p in parts if p is not None)


def captured_parts(frame, sample):
    """The ``LitPart``s the frame's techniques give a capture of ``sample`` (``Feature.capture``)."""
    return tuple(p for p in (f.capture(frame, sample) for f in frame.features) if p is not None)


def across_samples(frame, what, instead):
    """Whether ``frame`` has several samples to spread ``what`` over; a one-sample frame is
    drawn ``instead``, and its report says so."""
    if frame.accumulate:
        return True
    frame.stats.messages.append(f"Penumbra: {what} needs 2 or more samples: one sample is drawn {instead}")
    return False
