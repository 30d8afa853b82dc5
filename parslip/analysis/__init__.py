"""Reading runs back: rupture fronts, results object, figures, paper comparison, accuracy.  Never imports the engine."""
from .fronts import Front, break_events, first_break, fronts, load_interface, summary  # noqa: F401


def spacetime_png(iface: dict, png: str, title: str = "") -> bool:
    """The run's space-time picture with axes (``figures.spacetime_picture``); False for a free block."""
    from .figures import spacetime_picture
    return spacetime_picture(iface, png, title)
