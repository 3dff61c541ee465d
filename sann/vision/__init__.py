"""Vision for the multi-cup task: the cup, the camera, piles in a box, rendering, labels.

Modules: ``cup`` (the revolved mesh), ``camera`` (intrinsics, poses, projections), ``piles``
(the box and MuJoCo drops), ``render`` (embree depth/colour/instance images), ``labels``
(visible fractions, graspability, which cup lies on which).
"""
