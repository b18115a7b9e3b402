import bpy

STACK = r"""
{
 "format": 1,
 "layers": [
  {
   "effect": "FISHEYE",
   "name": "Tube bulge",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "strength": 0.25,
    "edge": "BLACK"
   }
  },
  {
   "effect": "BLUR",
   "name": "Phosphor",
   "enabled": true,
   "solo": false,
   "mix": 0.35,
   "params": {
    "radius": 1,
    "sigma": 0.0
   }
  },
  {
   "effect": "SCANLINES",
   "name": "Scanlines",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "count": 220,
    "thickness": 0.45,
    "intensity": 0.6,
    "scroll_speed": 0.05,
    "antialias": true
   }
  },
  {
   "effect": "NOISE",
   "name": "Signal noise",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "amount": 0.04,
    "size": 1,
    "monochrome": true,
    "seed": 0
   }
  },
  {
   "effect": "VIGNETTE",
   "name": "Tube edge",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "radius": 0.9,
    "softness": 0.5,
    "roundness": 0.6,
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
