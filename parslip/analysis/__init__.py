"""Reading runs back: rupture fronts, results object, figures, paper comparison, accuracy.  Never imports the engine."""
from .fronts import Front, break_events, first_break, fronts, load_interface, spacetime_png, summary  # noqa: F401
