import bpy

STACK = r"""
{
 "format": 1,
 "layers": [
  {
   "effect": "SEPIA",
   "name": "Sepia",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "amount": 0.85
   }
  },
  {
   "effect": "NOISE",
   "name": "Grain",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "amount": 0.08,
    "size": 2,
    "monochrome": true,
    "seed": 0
   }
  },
  {
   "effect": "SCANLINES",
   "name": "Gate flicker",
   "enabled": true,
   "solo": false,
   "mix": 0.5,
   "params": {
    "count": 3,
    "thickness": 0.1,
    "intensity": 0.15,
    "scroll_speed": 0.37,
    "antialias": true
   }
  },
  {
   "effect": "VIGNETTE",
   "name": "Burn",
   "enabled": true,
   "solo": false,
   "mix": 1.0,
   "params": {
    "radius": 0.6,
    "softness": 0.9,
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
