"""Reading runs back: rupture fronts, friction observables (static peak, precursors), results object,
a sweep's summary table.  Never imports the engine; pictures are ``parslip.plot``'s."""
from .fronts import Front, break_events, first_break, fronts, load_interface  # noqa: F401
from .friction import summary  # noqa: F401

