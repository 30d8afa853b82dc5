"""Pictures: the layer above ``analysis``, which reads measures and draws them (matplotlib, pyvista).

``figures`` the paper's figure set for one run and the run's space-time picture; ``maps`` an observable of
a sweep over two keys (``parslip map``); ``render`` whole-lattice snapshots off screen (``parslip render``);
``scene_picture`` the model picture of a scene (``parslip draw``, the docs' model figure); ``provenance``
the scene(s) and commit stamped into every picture.  Measures belong to ``analysis`` (the tip profile and
the Mode II fit that ``figures`` still computes are the exception the paper's measures read).  Importing
this package loads no plotting library.
"""


def spacetime_png(iface: dict, png: str, title: str = "") -> bool:
    """The run's space-time picture with axes (``figures.spacetime_picture``); False for a free block."""
    from .figures import spacetime_picture
    return spacetime_picture(iface, png, title)
