"""Multiple-scales analysis of the reduced 3-DOF chain-drive model of seed 004
(Fuglede & Thomsen 2016, JSV 366:447-470, sections 5.9-5.12 and 6).

* :mod:`.coefficients` - the non-dimensional coefficients of eqs 68-71 from a drive and Table 2;
"""

from .coefficients import (PARAMETER_NAMES, TABLE2, Coefficients, coefficients,
                           internal_resonance_check, reference_tension, table2)

__all__ = ["PARAMETER_NAMES", "TABLE2", "Coefficients", "coefficients",
           "internal_resonance_check", "reference_tension", "table2"]
