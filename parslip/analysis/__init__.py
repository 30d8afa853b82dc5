"""Reading runs back: generic measures grouped by quantity, each a function of the run (``results.Run``,
``parslip.open``'s object) that reads no file and draws nothing:

  fronts      the one front detector, the catalogue and its registry of per-front fields, front speeds
  friction    mu(t), the static peak, what became of each front (fate), precursors, stick-slip events
  rupture     measures of rupture as a crack: Andrews' S, daughters, patches, the shear-traction drop
  slip        slip at a site: slip velocity, the slip a front's passage carries
  cracks      fronts as cracks: the energy release rate G by two routes, and Gamma

Beside them: ``results`` (the run object), ``table`` (a sweep's summary table).  Importing the package
registers every per-front field (``fronts.FIELDS``).  Never imports the engine; pictures are
``parslip.plot``'s, the paper's claims ``parslip.studies.paper``'s."""
from . import cracks, friction, rupture, slip  # noqa: F401  (their per-front fields register on import)
from .fronts import Front, first_break, fronts  # noqa: F401
from .friction import summary  # noqa: F401

