"""Non-dimensional coefficients of the 3-DOF model of seed 004 (Fuglede & Thomsen 2016, JSV
366:447-470, eqs 68-70), computed from a drive and Table 2-style parameters.

Every symbol follows the paper; where the paper reuses a letter we name by meaning in code
(``alpha`` here is the stiffness ratio EA/P_t of eq 30, never a pitch angle; the Galerkin mode is
``mode``, never N).

Reading of the paper used here (each choice is argued in docs/perturbation.md):

* steady tensions, eqs 15-17:  P0 = (P_tot + M1/R1)/2,  P0~ = (P_tot - M1/R1)/2,
  M1 = d1 S / R1 + R1 f1, with S the mean chain speed n_driver p (rpm/60) and R1 the driven
  (index o, 1) pitch radius;
* lengths scale with l = |OC|, the centre distance (eq 26, nomenclature "l");
* time scales with sqrt(rhoA l^2 / P_t) (eq 27).  The paper leaves P_t open; the default here is
  P_t = P_tot/2, the static pretension of each span: it does not change with speed or load (so
  one time unit serves a whole speed sweep), and it is the value at which the Table 2 sprocket
  damping d1 = 1.1 N m s/rad and the Table 2 mu_theta = 0.02 agree (d/(2J) = 0.021, eq 71);
* the driver excitation amplitude theta2* is turned into the axial amplitude p2 of eq 86 by the
  kinematic relation of eq 51: p2 = R2 theta2* / l, with R2 the driver pitch radius;
* the slack span uses the tight span's damping mu_m and, unless told otherwise, the same mode
  number (Table 2 gives neither).

The modulation analysis (stationary.py, modulation.py) and the direct integration of eqs 68-70
(direct.py) take their numbers from :class:`Coefficients`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field
from typing import Mapping

__all__ = ["TABLE2", "PARAMETER_NAMES", "Coefficients", "coefficients", "table2",
           "internal_resonance_check", "reference_tension"]

#: the reference CSV (chainmodel/data) holding seed 004 Table 2
TABLE2 = "dynamic_params_jsv2016_table2.csv"

#: Table 2 names, SI unit, meaning, and whether zero is allowed
PARAMETER_NAMES: dict[str, tuple[str, str, bool]] = {
    "P_tot": ("N", "total pretension of both spans at rest", False),
    "EA": ("N", "axial stiffness of the chain", False),
    "rhoA": ("kg/m", "chain mass per unit length", False),
    "J1": ("kg m^2", "driven sprocket + machinery inertia", False),
    "f1": ("N", "brake load at the driven pitch radius", True),
    "d1": ("N m s/rad", "driven sprocket rotational viscous damping", True),
    "theta2_star": ("rad", "driver angular excitation amplitude", True),
    "mu_theta": ("-", "non-dimensional sprocket damping (eq 70)", True),
    "mu_m": ("-", "non-dimensional modal damping (eq 68)", True),
}

_P_T_CHOICES = ("pretension", "tight", "total")


def table2() -> dict[str, float]:
    """Seed 004 Table 2 as a dict (a fresh copy)."""
    from ...presets import reference_values
    return dict(reference_values(TABLE2))


def _finite(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def _check_params(params: Mapping[str, float] | None) -> dict[str, float]:
    merged = table2()
    if params is not None:
        unknown = sorted(set(params) - set(PARAMETER_NAMES))
        if unknown:
            raise ValueError(f"unknown dynamic parameter(s) {unknown}; valid names (seed 004 "
                             f"Table 2): {', '.join(PARAMETER_NAMES)}")
        merged.update(params)
    out = {}
    for name, (unit, meaning, zero_ok) in PARAMETER_NAMES.items():
        v = _finite(f"{name} ({meaning})", merged[name])
        if v < 0 or (v == 0 and not zero_ok):
            bound = ">= 0" if zero_ok else "> 0"
            raise ValueError(f"{name} ({meaning}) must be {bound} {unit}, got {v!r}")
        out[name] = v
    return out


def _check_mode(name: str, mode) -> int:
    if isinstance(mode, bool) or not isinstance(mode, numbers.Real) or not float(mode).is_integer():
        raise ValueError(f"{name} must be a whole number >= 1 (the Galerkin mode of eq 57), "
                         f"got {mode!r}")
    if mode < 1:
        raise ValueError(f"{name} must be a whole number >= 1 (the Galerkin mode of eq 57), "
                         f"got {mode!r}")
    return int(mode)


def _steady_state(drive, p: Mapping[str, float], speed_rpm: float):
    """Chain speed S, output torque M1 (eq 17) and the span tensions P0, P0~ (eqs 15-16)."""
    R1 = drive.driven.pitch_radius
    S = drive.n_driver * drive.pitch * speed_rpm / 60.0
    M1 = p["d1"] * S / R1 + R1 * p["f1"]
    P0 = 0.5 * (p["P_tot"] + M1 / R1)
    P0s = 0.5 * (p["P_tot"] - M1 / R1)
    return S, M1, P0, P0s


def reference_tension(P_t, params: Mapping[str, float], P0: float) -> float:
    """P_t of eq 27 from a number [N] or a name: 'pretension' = P_tot/2 (default),
    'tight' = P0 (eq 15, then alpha gamma = 1), 'total' = P_tot."""
    if isinstance(P_t, str):
        if P_t == "pretension":
            return 0.5 * params["P_tot"]
        if P_t == "tight":
            return P0
        if P_t == "total":
            return params["P_tot"]
        raise ValueError(f"P_t must be a positive tension in N or one of {', '.join(_P_T_CHOICES)},"
                         f" got {P_t!r}")
    v = _finite("P_t (reference tension of eq 27)", P_t)
    if v <= 0:
        raise ValueError(f"P_t (reference tension of eq 27) must be > 0 N, got {v!r}")
    return v


@dataclass(frozen=True)
class Coefficients:
    """All coefficients of eqs 68-71 for one drive, parameter set, speed and mode.

    Dimensional quantities carry their SI unit in the name's docstring; every other field is
    non-dimensional (lengths in units of ``length`` = l, times in units of ``time_unit``).
    """

    # --- inputs ---------------------------------------------------------------------------
    drive_name: str
    speed_rpm: float                #: driver speed [rpm]
    mode: int                       #: tight-span Galerkin mode m (eq 57)
    slack_mode: int                 #: slack-span Galerkin mode n
    params: dict = field(repr=False)  #: the Table 2-style parameters used
    # --- dimensional scales and steady state (eqs 15-17, 26-27) ---------------------------
    length: float                   #: l = |OC| [m] (eq 26)
    R1: float                       #: driven pitch radius [m]
    R2: float                       #: driver pitch radius [m]
    P_t: float                      #: reference tension [N] (eq 27)
    time_unit: float                #: sqrt(rhoA l^2 / P_t) [s]: one non-dimensional time (eq 27)
    chain_speed: float              #: S = n_driver p rpm/60 [m/s]
    M1_hat: float                   #: steady output torque (eq 17) [N m]
    P0: float                       #: tight-span steady tension (eq 15) [N]
    P0_slack: float                 #: slack-span steady tension (eq 16) [N]
    # --- non-dimensional (eqs 30, 53, 61, 71, 51) -----------------------------------------
    s: float                        #: S / sqrt(P_t/rhoA) (eq 30)
    alpha: float                    #: EA / P_t (eq 30)
    gamma: float                    #: P0 / EA (eq 30)
    gamma_slack: float              #: P0~ / EA (eq 30)
    J: float                        #: J1 / (rhoA l R1^2) (eq 53)
    d: float                        #: d1 / (R1^2 sqrt(rhoA P_t)) (eq 53)
    M1: float                       #: M1_hat / (R1 P_t) (eq 53)
    omega_m: float                  #: sqrt((alpha gamma - s^2)) m pi (eq 61)
    omega_n_slack: float            #: sqrt((alpha gamma~ - s^2)) n pi (eq 61 for the slack span)
    omega_theta: float              #: sqrt(2 alpha / J) (eq 71)
    alpha_m: float                  #: (m pi)^2 alpha (eq 61)
    alpha_n_slack: float            #: (n pi)^2 alpha
    kappa_m: float                  #: (m pi)^4 alpha / 4 (eq 61)
    kappa_n_slack: float            #: (n pi)^4 alpha / 4
    eta_m: float                    #: alpha (m pi)^2 / (4 J) (eq 71)
    eta_n_slack: float              #: alpha (n pi)^2 / (4 J) (eq 71)
    mu_m: float                     #: modal damping (Table 2)
    mu_n_slack: float               #: slack modal damping (= mu_m: Table 2 gives one value)
    mu_theta: float                 #: sprocket damping (Table 2)
    mu_theta_from_d: float          #: d / (2 J) (eq 71) from d1, for comparison with mu_theta
    p2: float                       #: R2 theta2* / l (eqs 51, 86)
    # --- dimensional frequencies [rad/s] ----------------------------------------------------
    omega_m_dim: float              #: tight-span mode frequency [rad/s]
    omega_n_slack_dim: float        #: slack-span mode frequency [rad/s]
    omega_theta_dim: float          #: driven-sprocket torsional frequency [rad/s]
    driver_rotation_dim: float      #: driver angular speed 2 pi rpm/60 [rad/s]
    tooth_frequency_dim: float      #: driver tooth (meshing) frequency n_driver * rpm/60 * 2pi [rad/s]

    # convenience -----------------------------------------------------------------------------
    @property
    def frequency_unit(self) -> float:
        """1 / time_unit [1/s]: multiply a non-dimensional frequency by this to get rad/s."""
        return 1.0 / self.time_unit

    def to_dimensional_frequency(self, omega):
        """Non-dimensional frequency -> rad/s."""
        return omega / self.time_unit

    def to_nondimensional_frequency(self, omega_rad_s):
        """rad/s -> non-dimensional frequency (eq 27)."""
        return omega_rad_s * self.time_unit

    @property
    def sigma_i(self) -> float:
        """Internal-resonance detuning omega_theta - 2 omega_m (eq 125 with epsilon = 1)."""
        return self.omega_theta - 2.0 * self.omega_m

    def as_dict(self) -> dict:
        d = asdict(self)
        d["frequency_unit"] = self.frequency_unit
        d["sigma_i"] = self.sigma_i
        return d

    def table(self) -> list[tuple[str, float, str, str, str]]:
        """(symbol, value, unit, equation, meaning) rows, for docs and the CLI."""
        return [
            ("l", self.length, "m", "26", "length unit: centre distance OC"),
            ("R1", self.R1, "m", "51", "driven pitch radius"),
            ("R2", self.R2, "m", "51", "driver pitch radius"),
            ("S", self.chain_speed, "m/s", "17", "mean chain speed n_c p rpm/60"),
            ("M1_hat", self.M1_hat, "N m", "17", "steady output torque d1 S/R1 + R1 f1"),
            ("P0", self.P0, "N", "15", "tight-span steady tension"),
            ("P0~", self.P0_slack, "N", "16", "slack-span steady tension"),
            ("P_t", self.P_t, "N", "27", "reference tension"),
            ("time unit", self.time_unit, "s", "27", "sqrt(rhoA l^2/P_t)"),
            ("s", self.s, "-", "30", "chain speed"),
            ("alpha", self.alpha, "-", "30", "EA/P_t"),
            ("gamma", self.gamma, "-", "30", "P0/EA"),
            ("gamma~", self.gamma_slack, "-", "30", "P0~/EA"),
            ("J", self.J, "-", "53", "J1/(rhoA l R1^2)"),
            ("d", self.d, "-", "53", "d1/(R1^2 sqrt(rhoA P_t))"),
            ("M1", self.M1, "-", "53", "M1_hat/(R1 P_t)"),
            ("omega_m", self.omega_m, "-", "61", "tight-span mode frequency"),
            ("omega~_n", self.omega_n_slack, "-", "61", "slack-span mode frequency"),
            ("omega_theta", self.omega_theta, "-", "71", "sprocket torsional frequency sqrt(2 alpha/J)"),
            ("alpha_m", self.alpha_m, "-", "61", "parametric coefficient (m pi)^2 alpha"),
            ("kappa_m", self.kappa_m, "-", "61", "cubic coefficient (m pi)^4 alpha/4"),
            ("eta_m", self.eta_m, "-", "71", "span-to-sprocket coupling alpha (m pi)^2/(4J)"),
            ("alpha~_n", self.alpha_n_slack, "-", "61", "slack parametric coefficient"),
            ("kappa~_n", self.kappa_n_slack, "-", "61", "slack cubic coefficient"),
            ("eta~_n", self.eta_n_slack, "-", "71", "slack coupling"),
            ("mu_m", self.mu_m, "-", "68", "modal damping (Table 2)"),
            ("mu_theta", self.mu_theta, "-", "70", "sprocket damping (Table 2)"),
            ("d/(2J)", self.mu_theta_from_d, "-", "71", "sprocket damping implied by d1"),
            ("p2", self.p2, "-", "51, 86", "driver excitation amplitude R2 theta2*/l"),
            ("sigma_i", self.sigma_i, "-", "125", "omega_theta - 2 omega_m"),
            ("omega_m", self.omega_m_dim, "rad/s", "61", "tight-span mode frequency"),
            ("omega~_n", self.omega_n_slack_dim, "rad/s", "61", "slack-span mode frequency"),
            ("omega_theta", self.omega_theta_dim, "rad/s", "71", "sprocket torsional frequency"),
            ("driver speed", self.driver_rotation_dim, "rad/s", "-", "2 pi rpm/60"),
            ("tooth frequency", self.tooth_frequency_dim, "rad/s", "63", "2 pi n_c rpm/60"),
        ]


def coefficients(drive, params: Mapping[str, float] | None = None, speed_rpm: float = 400.0,
                 P_t: float | str = "pretension", mode: int = 1,
                 slack_mode: int | None = None) -> Coefficients:
    """The non-dimensional coefficients of eqs 68-71 (seed 004) for ``drive``.

    Parameters
    ----------
    drive : :class:`chainmodel.Drive` (e.g. ``chainmodel.preset("C1")``).
    params : Table 2-style dict (keys of :data:`PARAMETER_NAMES`); missing keys take the Table 2
        value, unknown keys are an error. ``None`` is Table 2.
    speed_rpm : driver speed [rpm] >= 0; sets the chain speed S (eq 30) and, through the
        damping torque of eq 17, the span tensions.
    P_t : reference tension of eq 27 [N], or 'pretension' (P_tot/2, default), 'tight' (P0),
        'total' (P_tot).
    mode, slack_mode : Galerkin mode numbers m (tight) and n (slack, default m), >= 1.

    Raises ValueError naming the parameter for non-finite or out-of-range input, for a load the
    pretension cannot carry (slack-span tension P0~ <= 0, eq 16) and for a speed at which a
    span loses its transverse stiffness (alpha gamma <= s^2, eq 61).
    """
    p = _check_params(params)
    speed_rpm = _finite("speed_rpm (driver speed)", speed_rpm)
    if speed_rpm < 0:
        raise ValueError(f"speed_rpm (driver speed) must be >= 0 rpm, got {speed_rpm!r}")
    mode = _check_mode("mode", mode)
    slack_mode = mode if slack_mode is None else _check_mode("slack_mode", slack_mode)

    l = drive.centre_distance
    R1 = drive.driven.pitch_radius
    R2 = drive.driver.pitch_radius
    S, M1_hat, P0, P0s = _steady_state(drive, p, speed_rpm)
    if P0s <= 0:
        raise ValueError(
            f"P_tot = {p['P_tot']:g} N is too small for the load: the slack span's steady tension "
            f"(P_tot - M1/R1)/2 = {P0s:.4g} N (eq 16) must be positive, so P_tot must exceed "
            f"M1/R1 = {M1_hat / R1:.4g} N (brake load f1 = {p['f1']:g} N plus damping d1 S/R1^2 "
            f"= {p['d1'] * S / R1**2:.4g} N at {speed_rpm:g} rpm)")
    Pt = reference_tension(P_t, p, P0)
    EA, rhoA = p["EA"], p["rhoA"]
    for name, tension in (("tight", P0), ("slack", P0s)):
        if tension - rhoA * S**2 <= 0:
            raise ValueError(
                f"speed_rpm = {speed_rpm:g} is too high: the {name} span's tension {tension:.4g} N "
                f"does not exceed rhoA S^2 = {rhoA * S**2:.4g} N, so its transverse stiffness "
                f"(alpha gamma - s^2, eq 61) vanishes; lower the speed or raise P_tot")

    time_unit = math.sqrt(rhoA * l**2 / Pt)                       # eq 27
    s = S / math.sqrt(Pt / rhoA)                                  # eq 30
    alpha = EA / Pt
    gamma, gamma_s = P0 / EA, P0s / EA
    J = p["J1"] / (rhoA * l * R1**2)                              # eq 53
    d = p["d1"] / (R1**2 * math.sqrt(rhoA * Pt))
    M1 = M1_hat / (R1 * Pt)
    mpi, npi = mode * math.pi, slack_mode * math.pi
    omega_m = math.sqrt(alpha * gamma - s**2) * mpi               # eq 61
    omega_n = math.sqrt(alpha * gamma_s - s**2) * npi
    omega_theta = math.sqrt(2.0 * alpha / J)                      # eq 71
    rpm_to_rad = 2.0 * math.pi / 60.0
    return Coefficients(
        drive_name=drive.name, speed_rpm=speed_rpm, mode=mode, slack_mode=slack_mode, params=p,
        length=l, R1=R1, R2=R2, P_t=Pt, time_unit=time_unit, chain_speed=S, M1_hat=M1_hat,
        P0=P0, P0_slack=P0s,
        s=s, alpha=alpha, gamma=gamma, gamma_slack=gamma_s, J=J, d=d, M1=M1,
        omega_m=omega_m, omega_n_slack=omega_n, omega_theta=omega_theta,
        alpha_m=mpi**2 * alpha, alpha_n_slack=npi**2 * alpha,
        kappa_m=mpi**4 * alpha / 4.0, kappa_n_slack=npi**4 * alpha / 4.0,
        eta_m=alpha * mpi**2 / (4.0 * J), eta_n_slack=alpha * npi**2 / (4.0 * J),
        mu_m=p["mu_m"], mu_n_slack=p["mu_m"], mu_theta=p["mu_theta"],
        mu_theta_from_d=d / (2.0 * J),
        p2=R2 * p["theta2_star"] / l,                             # eq 51
        omega_m_dim=omega_m / time_unit, omega_n_slack_dim=omega_n / time_unit,
        omega_theta_dim=omega_theta / time_unit,
        driver_rotation_dim=speed_rpm * rpm_to_rad,
        tooth_frequency_dim=drive.n_driver * speed_rpm * rpm_to_rad,
    )


def internal_resonance_check(drive, params: Mapping[str, float] | None = None,
                             speed_rpm: float = 400.0, mode: int = 1, ratio: float = 2.0,
                             max_rpm: float = 5000.0) -> dict:
    """What the claim "at 400 rpm the tight span and the driven sprocket are in internal
    resonance" (seed 004 section 6) means for these parameters.

    Returns omega_theta / omega (tight and slack span, eq 71 over eq 61) at ``speed_rpm`` and,
    for each span, the driver speed at which omega_theta = ``ratio`` * omega holds (None if no
    speed in [0, max_rpm] where the spans stay taut gives it). The ratios do not depend on P_t.
    """
    from scipy.optimize import brentq

    c = coefficients(drive, params, speed_rpm, mode=mode)

    def mismatch(rpm, span):
        k = coefficients(drive, c.params, rpm, mode=mode)
        om = k.omega_m if span == "tight" else k.omega_n_slack
        return k.omega_theta / om - ratio

    out = {"speed_rpm": speed_rpm, "ratio": ratio,
           "tight": c.omega_theta / c.omega_m, "slack": c.omega_theta / c.omega_n_slack,
           "omega_theta_rad_s": c.omega_theta_dim, "omega_m_rad_s": c.omega_m_dim,
           "omega_n_slack_rad_s": c.omega_n_slack_dim}
    # largest speed at which both spans stay taut (P0~ > 0 and P - rhoA S^2 > 0)
    lo, hi = 0.0, max_rpm
    def valid(rpm):
        try:
            coefficients(drive, c.params, rpm, mode=mode)
            return True
        except ValueError:
            return False
    if not valid(hi):
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if valid(mid) else (lo, mid)
        hi = lo
    grid = [hi * k / 400 for k in range(401)]
    for span in ("tight", "slack"):
        vals = [mismatch(r, span) for r in grid]
        root = None
        for r0, r1, v0, v1 in zip(grid, grid[1:], vals, vals[1:]):
            if v0 == 0:
                root = r0
                break
            if v0 * v1 < 0:
                root = brentq(mismatch, r0, r1, args=(span,), xtol=1e-6)
                break
        out[f"{span}_speed_rpm_at_ratio"] = root
    return out
