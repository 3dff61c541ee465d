"""Views of SANN: 3D meshcat scenes (`meshcat_scenes`, embedded offline by `embed`), the
architecture diagram (`diagrams`) and the paper's 2D figures (`plots`).

Submodules are imported on demand so that drawing a plot never pays for loading meshcat.
"""
