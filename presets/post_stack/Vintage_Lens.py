import bpy

STACK = r"""
{
 "format": 1,
 "layers": [
  {
   "effect": "LENS_FLARE",
   "name": "Flare",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "threshold": 0.8,
    "intensity": 0.6,
    "mode": "SCREEN",
    "ghosts": 5,
    "ghost_spacing": 0.4,
    "halo_radius": 0.6,
    "halo_width": 0.1,
    "image": null
   }
  },
  {
   "effect": "COLORIZER",
   "name": "Warm grade",
   "enabled": true,
   "solo": false,
   "mix": 0.5,
   "params": {
    "image": null,
    "blur_radius": 2,
    "strength": 0.6
   }
  },
  {
   "effect": "FISHEYE",
   "name": "Barrel",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "strength": 0.12,
    "edge": "CLAMP"
   }
  },
  {
   "effect": "VIGNETTE",
   "name": "Vignette",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "radius": 0.75,
    "softness": 0.7,
    "roundness": 1.0,
    "color": [
     0.05,
     0.03,
     0.02
    ]
   }
  }
 ]
}
"""

bpy.ops.penumbra.post_stack_apply(stack=STACK)
