import bpy

STACK = r"""
{
 "format": 1,
 "layers": [
  {
   "effect": "GLOW",
   "name": "Glow",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "threshold": 0.6,
    "knee": 0.5,
    "intensity": 0.8,
    "radius": 12,
    "square_samples": false
   }
  },
  {
   "effect": "BLUR",
   "name": "Diffusion",
   "enabled": true,
   "solo": false,
   "mix": 0.2,
   "params": {
    "radius": 4,
    "sigma": 0.0
   }
  },
  {
   "effect": "VIGNETTE",
   "name": "Vignette",
   "enabled": true,
   "solo": false,
   "mix": 0.6,
   "params": {
    "radius": 1.0,
    "softness": 0.8,
    "roundness": 1.0,
    "color": [
     0.0,
     0.0,
     0.0
    ]
   }
  }
 ]
}
"""

bpy.ops.penumbra.post_stack_apply(stack=STACK)
