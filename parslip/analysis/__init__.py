"""Reading runs back: rupture fronts, friction observables (static peak, precursors), results object,
figures, a sweep's summary table and its maps, paper comparison, accuracy.  Never imports the engine."""
from .fronts import Front, break_events, first_break, fronts, load_interface  # noqa: F401
from .friction import summary  # noqa: F401


def spacetime_png(iface: dict, png: str, title: str = "") -> bool:
    """The run's space-time picture with axes (``figures.spacetime_picture``); False for a free block."""
    from .figures import spacetime_picture
    return spacetime_picture(iface, png, title)
