"""What the tools and the tests share (not shipped in the extension zip; never imports tests).

session        throw-away user folders, the repository as the ``penumbra`` package, GPU runner,
               leaving the process safely
scenes         scenes built in code: the demo scene, primitives, the box over a plane
engines        the one place that sets Penumbra, EEVEE, Cycles and Workbench up for a scene
render         render through Blender's output path to arrays; one frame of the engine core
imageio        image files through OpenImageIO, Blender's output formats on 4.5 and 5.x
timing         warm-up plus timed runs: median, min, max
report         CSV files and Markdown tables
analytic       camera rays, plane hits and box shadows in numpy
reference_kit  shadow reference scenes, visibility measurement, cached Cycles references
extension      the extension zip built with Blender's own tool

Modules that need ``bpy`` import it themselves; importing ``devkit`` imports nothing else.
"""
