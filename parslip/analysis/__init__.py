"""Reading runs back: rupture fronts, the space-time plot.  Never imports the engine."""
from .fronts import Front, break_events, first_break, fronts, load_interface, spacetime_png, summary  # noqa: F401
