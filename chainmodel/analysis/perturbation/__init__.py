"""Multiple-scales analysis of the reduced 3-DOF chain-drive model of seed 004
(Fuglede & Thomsen 2016, JSV 366:447-470, sections 5.9-5.12 and 6).

* :mod:`.coefficients` - the non-dimensional coefficients of eqs 68-71 from a drive and
  Table 2 (steady tensions eqs 15-17, scaling eqs 26-27, 30, 53, 61, 71, excitation eq 51);
* :mod:`.stationary` - closed-form stationary solutions and their stability: eq 105 with (106)
  and the Jacobian of eqs 100-101 (section 5.10), eq 121 (section 5.11), eq 140;
* :mod:`.modulation` - the modulation equations (100-101, 119-120, 129-132) integrated with
  ``solve_ivp`` for whole batches of detunings, Newton-polished fixed points and eigenvalues;
* :mod:`.direct` - direct integration of eqs 68-70 themselves, for validation;
* :mod:`.response` - frequency-response sweeps after Figs 6-9; :mod:`.plots` draws them;
* :mod:`.cli` - ``chainmodel frequency-response``.

docs/perturbation.md explains every modelling choice (P_t, l, Omega2, epsilon) and what could
and could not be reproduced.
"""

import importlib

# Names resolve lazily (PEP 562) so that importing the CLI hook (``.cli``), which every
# ``chainmodel`` call does, does not import scipy.
_EXPORTS = {
    "coefficients": ["PARAMETER_NAMES", "TABLE2", "Coefficients", "coefficients",
                     "internal_resonance_check", "reference_tension", "table2"],
    "direct": ["integrate_direct", "parametric_initial_state"],
    "modulation": ["POLICIES", "combined_coefficients", "integrate_combined",
                   "integrate_parametric", "integrate_sprocket", "polish_stationary",
                   "settle_combined"],
    "response": ["combined_response", "parametric_response", "sprocket_response"],
    "stationary": ["combined_trivial_amplitude", "parametric_branches",
                   "parametric_instability_band", "parametric_polar_jacobian",
                   "parametric_trivial_eigenvalues", "sprocket_amplitude"],
    "cli": ["register"],
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}
__all__ = list(_WHERE)

# The function ``coefficients`` shares its name with its module; bind it eagerly (the module
# is light) so that a later import of the submodule cannot shadow it.
from .coefficients import coefficients  # noqa: E402


def __getattr__(name):
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
