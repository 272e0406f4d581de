"""The fixed-step loop of levels 1 (torsional) and 2 (modal): the stable-step guard, the event
location and crossing, and the outputs, over one or many communication steps in one call
(numba; the same source as plain Python with ``CHAINMODEL_NUMBA=0``). The output sampling and
status loop, the held step and the RK4 and Verlet steps are this level's instances of the
sources in :mod:`chainmodel.kernels.stepping` (written once for every level: ``_points``,
``_held``, ``_rk4_from``, ``_verlet_from``); :func:`_advance` (one communication step:
:func:`_interval`) and :func:`_outputs` are what this level plugs into them. Every other
fixed-step run (a model without kernels, the ``integrate.python_loop_model`` twin) runs
these functions' own source on the model interface (:mod:`chainmodel.kernels.plain_loop`
rebinds the six names that touch the model: ``_rhs_at``, ``_switch``, ``_omega_at``,
``_event_step``, ``_after_step``, ``_step_from``).

**Inputs inside a communication step** [t0, t1]: the input-shaft angle is the cubic Hermite
interpolant of the (angle, speed) given at both ends, its acceleration the interpolant's second
derivative (or the given value when it is the same at both ends), the load torque linear. That is
exact for inputs held first-order (the FMU: angle1 = angle0 + speed0 (t1 - t0), speed, torque
and acceleration held) and for the scenes' ramp profiles whenever the ramp ends on a
communication point.

**Step rule** (docs/numerics.md). The internal step never depends on the communication step
except that a communication step shorter than it is taken whole (at level 1 several such, as
below). With ``cfg`` from
``chainmodel.integrate.FixedStepper.cfg`` (CF_*): an explicit ``solver.step`` is used as
given; otherwise the step bound is

    h_max = min(theta / w, safety * 2 sqrt(2) / w, max_step, quarter tooth period)

with w the highest natural frequency of the *current* state (:func:`omega_estimate`: the
sprockets' bound, and at level 2 each span's highest mode at its current tension), theta =
(120 tol)^(1/4) the RK4 step at which the relative phase error of that mode is ``tol``
(``solver.tolerance``), and the quarter tooth period at the larger input speed of the two ends of
the communication step (four seating and release events per tooth period; a step crosses only
the first event inside it). A communication step is split into m = ceil(H / h_max) equal steps;
after every step w is estimated again from the step's end (the evaluation the next step starts
with, so it costs nothing) and if the step now exceeds h_max the rest of the communication step
is split again (the stable-step guard). A step that outran the rule's estimate at its start
(:func:`_step_kept`: level 1's lagged sag moved by more than a factor of two, a span gone slack
inside the step) is retried at a quarter of its length, up to MAX_RETRIES times; the retries'
evaluations count, the steps do not. An explicit step with h w above RK4's stability limit
2 sqrt(2) is refused (status STATUS_UNSTABLE) instead.

**Steps spanning points** (level 1, a run through many points: :func:`_span_step`). Where
h_max, automatic, exceeds two or more intervals of the points ahead, one step is taken to the
last point within it, provided:

* the inputs given at the points in between lie on the cubic Hermite through the step's ends
  (held speed, a ramp), so the step sees what the steps point by point would;
* no switching function changes sign over it (else it is tried once more, to the last point
  before the change's secant estimate, and the points then step one by one past it);
* the state stays finite and the step is within h_max at its end too.

The points in between take the step's cubic Hermite dense output (:func:`_dense`, error of
order (w h)^4 / 384 of the mode's amplitude, below the tolerance's phase error) and are
evaluated at their own inputs. On C1 at 400 rpm (h_max 2.85 ms, outputs every 0.1 ms) this
cuts level 1's evaluations per point from 4.6 to 2.6, the outputs within 1-2 % of their
ripple of the steps point by point (docs/numerics.md). Level 2 keeps the steps point by
point: near a span's parametric resonance its time series depends on the step as on any tiny
change of the problem (docs/numerics.md, "Level 2 on C1 at 400 rpm"), and the steps point by
point keep its runs what they were. The held step (the FMU) has one interval: unchanged.

**Outputs** at each communication point come from the point's own inputs: the evaluation that
ends the last step is reused when its inputs are those (held inputs), otherwise the kernel is
evaluated once more. :func:`fill_outputs` maps the kernel's auxiliary values to the 15 outputs of
DESIGN.md in :data:`chainmodel.outputs.ALL_OUTPUTS` order.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit, jit_inline, jit_noalloc
from . import stepping
from .stepping import (STATUS_AMPLITUDE, STATUS_NONFINITE, STATUS_OK, STATUS_OUTPUTS,
                       STATUS_UNSTABLE, finite, instance)
from ..outputs import (N_OUTPUTS, O_CHAIN_MAX_LINK_TENSION, O_CHAIN_MIN_LINK_TENSION,  # noqa: F401
                      O_CONTACT_MAX_FORCE, O_DRIVEN_ACCELERATION, O_DRIVEN_ANGLE, O_DRIVEN_SPEED,
                      O_DRIVER_ANGLE, O_DRIVER_SPEED, O_INPUT_SHAFT_TORQUE, O_SLACK_SPAN_TENSION,
                      O_TIGHT_SPAN_LENGTH, O_TIGHT_SPAN_MIDSPAN_DEFLECTION, O_TIGHT_SPAN_TENSION,
                      O_TRANSMISSION_ERROR, O_VELOCITY_RATIO)
from .spans import (A_ACC2, A_G_UP, A_L_LOW, A_L_UP, A_MID_LOW, A_MID_UP, A_PHI1, A_SIZE,
                    A_T_LOW, A_T_UP, A_TAU_IN, A_W1, P_LBAR_L, P_LBAR_U, P_MODES, P_PITCH,
                    P_RHOA, P_RIGID, evaluate, evaluate_rate)
from .spans import A_LAG_W, A_LOWER_TIGHT, P_LAG, lag_index, lag_step_kept

__all__ = ["C_SIZE", "CF_SIZE", "Q_SIZE", "advance_points", "advance_held", "outputs_into",
           "outputs_many", "omega_estimate", "fill_outputs", "EVENT_TOL", "EVENT_GAP",
           "STATUS_OK", "STATUS_NONFINITE", "STATUS_UNSTABLE", "STATUS_AMPLITUDE",
           "STATUS_OUTPUTS"]

# --- the inputs of one communication step ------------------------------------------------------
C_T0, C_DT, C_A0, C_W0, C_A1, C_W1, C_ACC0, C_ACC1, C_L0, C_L1 = range(10)
#: the inputs last interpolated (:func:`_inputs_at`): at time c[C_IN_T] (NaN: none yet), the
#: angle, speed, acceleration and load there
C_IN_T, C_IN_TH, C_IN_W, C_IN_ACC, C_IN_LOAD = range(10, 15)
#: a step spanning several communication points (:func:`_span_step`): its start time and
#: length, the index of the point it ends on (-1: none under way), and the last point of an
#: attempt an event refused (no new attempt up to it)
C_SEG_T0, C_SEG_H, C_SEG_END, C_SEG_BLOCK = range(15, 19)
C_SIZE = 19

# --- step rule (FixedStepper.cfg) ----------------------------------------------
#: explicit step (0: automatic), theta = h w of the tolerance, safety * stability limit, the
#: stability limit itself (2 sqrt 2), an outer bound on the automatic step
CF_STEP, CF_THETA, CF_STAB, CF_LIMIT, CF_MAX = range(5)
CF_SIZE = 5

# --- model constants of the loop (TorsionalModel.loop_constants) ------------------------------
#: sprockets' highest natural frequency (bound), tooth ratio n_driver / n_driven, the level-1
#: quasi-static sag coefficient rho g_n / 8, the span-mode amplitude limit of ModalModel.check
#: (inf at level 1), a quarter of the driver's tooth angle (2 pi / n_driver) / 4
Q_W_SPROCKET, Q_RATIO, Q_SAG, Q_AMP_LIMIT, Q_EVENT_ANGLE, Q_CENTRIFUGAL = range(6)
Q_SIZE = 6


W_ROWS = 18     # work vectors of the state's size (see _interval; 14-17: _span_step's ends)
V_ROWS = 9      # work vectors of the 6 switching functions: g0, g1, gh, gm, glo, flo, fhi, ga, gb

# Event crossing: the root
# tolerance on a dense output and the gap eta between the steps on either side of an event, both
# relative to the step h (docs/reduced_models.md, "Numerics").
EVENT_TOL = 1e-5
EVENT_GAP = 1e-4



@jit_noalloc
def _inputs(t, c):
    dt = c[C_DT]
    s = (t - c[C_T0]) / dt
    s2 = s * s
    s3 = s2 * s
    a0 = c[C_A0]
    a1 = c[C_A1]
    w0 = c[C_W0]
    w1 = c[C_W1]
    th = ((2 * s3 - 3 * s2 + 1) * a0 + (s3 - 2 * s2 + s) * dt * w0 + (3 * s2 - 2 * s3) * a1
          + (s3 - s2) * dt * w1)
    w = ((6 * s2 - 6 * s) / dt * a0 + (3 * s2 - 4 * s + 1) * w0 + (6 * s - 6 * s2) / dt * a1
         + (3 * s2 - 2 * s) * w1)
    if c[C_ACC0] == c[C_ACC1]:
        acc = c[C_ACC0]     # held or constant: the source's own value
    else:
        acc = ((12 * s - 6) * a0 + (6 * s - 4) * dt * w0 + (6 - 12 * s) * a1
               + (6 * s - 2) * dt * w1) / (dt * dt)
    load = c[C_L0] + (c[C_L1] - c[C_L0]) * s
    return th, w, acc, load


@jit_noalloc
def _inputs_at(t, c):
    """:func:`_inputs`, remembered in c for the last t: RK4's two middle stages share their
    time, and its last stage's is the step end's (the switching functions' evaluation)."""
    if t != c[C_IN_T]:
        th, w, acc, load = _inputs(t, c)
        c[C_IN_T] = t
        c[C_IN_TH] = th
        c[C_IN_W] = w
        c[C_IN_ACC] = acc
        c[C_IN_LOAD] = load
    return c[C_IN_TH], c[C_IN_W], c[C_IN_ACC], c[C_IN_LOAD]


@jit_noalloc
def _rhs_at(t, x, c, G, P, dx, aux):
    """The derivative at (t, x) into ``dx``; aux is left partly stale (spans.evaluate_rate):
    in this loop every reader of aux (outputs, frequency, switching functions) follows a
    :func:`_switch`, the full evaluation."""
    th, w, acc, load = _inputs_at(t, c)
    evaluate_rate(x, th, w, acc, load, G, P, dx, aux)


#: the step rules, written once in chainmodel.kernels.stepping, on this level's right-hand side
_rk4_from = instance(stepping.rk4, "_rk4_from", __name__, _rhs_at=_rhs_at)
_verlet_from = instance(stepping.verlet, "_verlet_from", __name__, _rhs_at=_rhs_at)


#: the method's step from (t, x) with f(t, x) known, returning its new evaluations: RK4 in the
#: compiled loop of levels 1-2; chainmodel.models.loop_on_model rebinds it per method
_step_from = _rk4_from


@jit_noalloc
def _switch(t, x, c, G, P, dx, aux, g):
    th, w, acc, load = _inputs_at(t, c)
    evaluate(x, th, w, acc, load, G, P, dx, aux)
    for i in range(g.size):
        g[i] = aux[A_G_UP + i]


@jit_noalloc
def _changed(g, g0):
    for i in range(g.size):
        if g[i] * g0[i] < 0.0 and g[i] != 0.0 and g0[i] != 0.0:
            return True
    return False


@jit_noalloc
def _dense(x0, f0, x1, f1, H, s, out):
    """Dense output at s of a step from (x0, f0) at 0 to (x1, f1) at H: the cubic Hermite
    interpolant (an extrapolation for s > H); for H = 0 the line x0 + s f0."""
    if H == 0.0:
        for i in range(x0.size):
            out[i] = x0[i] + s * f0[i]
        return
    th = s / H
    th2 = th * th
    th3 = th2 * th
    a = 2.0 * th3 - 3.0 * th2 + 1.0
    b = (th3 - 2.0 * th2 + th) * H
    d = (th3 - th2) * H
    for i in range(x0.size):
        out[i] = a * x0[i] + b * f0[i] + (1.0 - a) * x1[i] + d * f1[i]


@jit_noalloc
def _secant(lo, hi, glo, ghi, g0):
    """Earliest secant root in [lo, hi] among the functions changed between g0 and ghi."""
    best = 1.0e300
    for i in range(g0.size):
        if ghi[i] * g0[i] < 0.0 and ghi[i] != 0.0 and g0[i] != 0.0:
            den = glo[i] - ghi[i]
            if den != 0.0:
                r = lo + (hi - lo) * glo[i] / den
                if r < best:
                    best = r
    if best == 1.0e300 or not math.isfinite(best):
        return 0.5 * (lo + hi)
    return min(max(best, lo), hi)


@jit_noalloc
def _locate(t, x0, f0, x1, f1, H, lo, hi, g_lo, g_hi, g0, tol, c, G, P, xm, dx, aux, V):
    """Earliest sign change (relative to g0) of the switching functions in [lo, hi] on the dense
    output :func:`_dense` (x0, f0; x1, f1; H), g_lo and g_hi the functions at the ends: safeguarded
    regula falsi (Illinois) to ``tol``, one evaluation per iteration. Returns (s, evaluations), s
    the secant root in the final bracket."""
    gh = V[2]
    gm = V[3]
    glo = V[4]
    flo = V[5]
    fhi = V[6]
    for i in range(g0.size):
        gh[i] = g_hi[i]
        glo[i] = g_lo[i]
        flo[i] = g_lo[i]
        fhi[i] = g_hi[i]
    side = 0
    evals = 0
    for _it in range(100):
        if hi - lo <= tol:
            break
        mid = 1.0e300
        for i in range(g0.size):
            if gh[i] * g0[i] < 0.0 and gh[i] != 0.0 and g0[i] != 0.0:
                den = flo[i] - fhi[i]
                if den != 0.0:
                    r = lo + (hi - lo) * flo[i] / den
                    if r < mid:
                        mid = r
        margin = 1e-3 * (hi - lo)
        if mid == 1.0e300 or not math.isfinite(mid):
            mid = 0.5 * (lo + hi)
        elif mid < lo + margin:
            mid = lo + margin
        elif mid > hi - margin:
            mid = hi - margin
        _dense(x0, f0, x1, f1, H, mid, xm)
        _switch(t + mid, xm, c, G, P, dx, aux, gm)
        evals += 1
        if _changed(gm, g0):
            hi = mid
            for i in range(g0.size):
                gh[i] = gm[i]
                fhi[i] = gm[i]
                if side == -1:
                    flo[i] = 0.5 * flo[i]
            side = -1
        else:
            lo = mid
            for i in range(g0.size):
                glo[i] = gm[i]
                flo[i] = gm[i]
                if side == 1:
                    fhi[i] = 0.5 * fhi[i]
            side = 1
    return _secant(lo, hi, glo, gh, g0), evals


@jit_noalloc
def _cross(t, x, h, t_end, c, G, P, W, V, aux):
    """The step [t, t_end] (h = t_end - t) from ``x`` (f(t, x) in W[3]) over which a switching
    function changed sign (plain step's end state and derivative in W[0], W[8], functions at both
    ends in V[0], V[1]), redone across the first change (docs/reduced_models.md, "Numerics"):

    1. a first estimate s of the change on the step's cubic Hermite dense output;
    2. one step of the method (``_step_from``) to sa = s - eta (eta = EVENT_GAP h), whose
       state must lie on the old side of every function (else s is searched again on the
       dense output of [t, t + sa]);
    3. s located again on the dense output of the old side alone, (x, f) at t and at t + sa
       extrapolated past sa - the plain step's end state straddled the kink, this does not;
       if s ends up more than 4 eta past sa, back to 2;
    4. across the change to sb = s + eta by the two one-sided slopes (the old side's f over
       [sa, s], the new side's over [s, sb]), sb widened until its state is on the new side;
    5. one step from sb to t + h, its first stage on the new side.

    No stage straddles the kink (that costs an error of order jump * h / 6, first order in
    h), and the crossing errs by order eta^2 f' + jump * (error of s). Leaves the state at t_end
    in W[0], f there in W[8] (evaluated at t_end itself), the functions there in V[1]. Returns
    (s, evaluations)."""
    n = x.size
    xn = W[0]
    xm = W[1]
    xb = W[2]
    k1 = W[3]
    k2 = W[4]
    k3 = W[5]
    k4 = W[6]
    tmp = W[7]
    f1 = W[8]
    xa = W[9]
    fa = W[10]
    xq = W[11]
    fq = W[12]
    fb = W[13]
    g0 = V[0]
    g1 = V[1]
    ga = V[7]
    gb = V[8]
    tol = EVENT_TOL * h
    eta = EVENT_GAP * h
    s, evals = _locate(t, x, k1, xn, f1, h, 0.0, h, g0, g1, g0, tol, c, G, P, xm, tmp, aux, V)
    sa = 0.0
    for _pass in range(8):
        # 2. to sa, on the old side
        for _it in range(20):
            sa = s - eta
            if sa <= 0.0:
                sa = 0.0
                break
            e = _step_from(t, x, sa, c, G, P, k1, k2, k3, k4, tmp, aux, xa)
            _switch(t + sa, xa, c, G, P, fa, aux, ga)
            evals += e + 1
            if not _changed(ga, g0):
                break
            s, e = _locate(t, x, k1, xa, fa, sa, 0.0, sa, g0, ga, g0, tol, c, G, P, xm, tmp,
                           aux, V)
            evals += e
        if sa == 0.0:
            for i in range(n):
                xa[i] = x[i]
                fa[i] = k1[i]
            for i in range(g0.size):
                ga[i] = g0[i]
        # 3. on the old side's dense output, extrapolated past sa
        sb = min(s + eta, h)
        for _it in range(60):
            _dense(x, k1, xa, fa, sa, sb, xm)
            _switch(t + sb, xm, c, G, P, tmp, aux, gb)
            evals += 1
            if _changed(gb, g0) or sb >= h:
                break
            sb = min(sa + 2.0 * (sb - sa), h)
        if not _changed(gb, g0):
            break                      # no change on the extrapolation: keep the estimate
        if sb - sa <= 4.0 * eta:
            s = _secant(sa, sb, ga, gb, g0)
        else:
            s, e = _locate(t, x, k1, xa, fa, sa, sa, sb, ga, gb, g0, tol, c, G, P, xm, tmp,
                           aux, V)
            evals += e
        if s - sa <= 4.0 * eta:
            break
    # 4. across the change by the one-sided slopes
    if s < sa:
        s = sa
    eta_b = eta
    sb = h
    for _it in range(60):
        sb = min(s + eta_b, h)
        for i in range(n):
            xq[i] = xa[i] + (sb - sa) * fa[i]
        _rhs_at(t + sb, xq, c, G, P, fq, aux)
        for i in range(n):
            xb[i] = xa[i] + (s - sa) * fa[i] + (sb - s) * fq[i]
        _switch(t_end if sb >= h else t + sb, xb, c, G, P, fb, aux, gb)
        evals += 2
        if _changed(gb, g0) or sb >= h:
            break
        eta_b *= 8.0
    # 5. the rest of the step
    if sb < h:
        e = _step_from(t + sb, xb, h - sb, c, G, P, fb, k2, k3, k4, tmp, aux, xn)
        _switch(t_end, xn, c, G, P, f1, aux, g1)
        evals += e + 1
    else:
        for i in range(n):
            xn[i] = xb[i]
            f1[i] = fb[i]
        for i in range(g0.size):
            g1[i] = gb[i]
    return s, evals


@jit_noalloc
def omega_estimate(aux, G, P, Q):
    """Highest natural frequency [rad/s] at the state of the evaluation ``aux``: the sprockets'
    bound Q_W_SPROCKET (stiffest spans, TorsionalModel.sprocket_frequencies) and, at level 2,
    the highest Galerkin mode of each span at its current tension,
    n pi / lbar sqrt((T - rho S^2) / rho) (seed 004 eq 61, dimensional). The span modes are
    what changes with the state: a tight span under load rings faster than at rest. Level 1's
    lagged sag (P_LAG): aux A_LAG_W, the larger of spans.LAG_SHARE times its decay rate and
    its state's relative rate |dT_q/dt| / T_q (spans._lagged), so a step moves the sag's
    tension by at most h w of itself; a tighter tolerance tightens it with the
    oscillations'."""
    w = Q[Q_W_SPROCKET]
    if P[P_LAG] > 0.5 and aux[A_LAG_W] > w:
        # level 1's lagged sag (spans._lagged: its decay's share, or its state's own rate)
        w = aux[A_LAG_W]
    n = int(P[P_MODES])
    if n > 0:
        rho = P[P_RHOA]
        speed = G[9] * P[P_PITCH] * aux[A_W1] / (2.0 * math.pi)
        for k in range(2):
            tension = aux[A_T_UP] if k == 0 else aux[A_T_LOW]
            lbar = P[P_LBAR_U] if k == 0 else P[P_LBAR_L]
            s = tension / rho - speed * speed
            if s > 0.0:
                wm = n * math.pi / lbar * math.sqrt(s)
                if wm > w:
                    w = wm
    return w


@jit_noalloc
def _step_bound(w, h_event, cfg):
    """h_max of the module docstring for the frequency w (automatic step)."""
    h = math.inf
    if w > 0.0:
        h = min(cfg[CF_THETA] / w, cfg[CF_STAB] / w)
    if cfg[CF_MAX] < h:
        h = cfg[CF_MAX]
    if h_event < h:
        h = h_event
    return h


@jit_noalloc
def _interval(x, t0, t1, c, G, P, Q, cfg, W, V, aux, log, log_at, log_cap, started):
    """RK4 from (t0, x) to t1, in place on ``x``, with the step rule and guard of the module
    docstring; a step over which a switching function changes sign is redone across the change
    (:func:`_cross`). The first ``log_cap`` located event times go to
    ``log[(log_at + k) % log.size]``. ``started``: W[3], V[0] and aux already hold the
    evaluation at (t0, x) with the step's inputs there (the previous step's last one), else it
    is made here. On return ``aux`` holds the evaluation at (t1, x), f in W[3], the switching
    functions in V[0].

    Returns (status, steps, events, rhs_evaluations, t, omega): status STATUS_OK, or
    :func:`_after_step`'s (STATUS_NONFINITE or STATUS_AMPLITUDE: stopped after the step that
    left the model's range, at time t, its state in ``x``) or
    STATUS_UNSTABLE (an explicit step above the stable limit of the state at t, nothing done
    from there; omega the frequency estimate there)."""
    n = x.size
    xn = W[0]
    k1 = W[3]
    k2 = W[4]
    k3 = W[5]
    k4 = W[6]
    tmp = W[7]
    f1 = W[8]
    g0 = V[0]
    g1 = V[1]
    evals = 0
    events = 0
    steps = 0
    t = t0
    if not started:
        _switch(t, x, c, G, P, k1, aux, g0)
        evals += 1
    h_event = _event_step(c, Q)
    fixed = cfg[CF_STEP] > 0.0
    h = 0.0
    retries = 0
    while t < t1:
        if retries == 0:
            w = _omega_at(t, x, aux, c, G, P, Q)
            if fixed:
                if cfg[CF_STEP] * w > cfg[CF_LIMIT]:
                    return STATUS_UNSTABLE, steps, events, evals, t, w
                h_max = cfg[CF_STEP]
            else:
                h_max = _step_bound(w, h_event, cfg)
        rest = t1 - t
        if h == 0.0 or h > h_max or h > rest:
            # first step, the guard, or round-off at the end: split the rest evenly
            m = max(1.0, math.ceil(rest / h_max - 1e-9))
            h = rest / m
        if h >= rest * (1.0 - 1e-12):
            t_next = t1
            h = rest
        else:
            t_next = t + h
        # k1 = f(t, x): the previous evaluation at this (t, x), the switch at the step end
        e = _step_from(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, xn)
        evals += e
        if retries < MAX_RETRIES and not _step_kept(x, xn, c, P):
            # the step outran the rule's estimate at its start (_step_kept): again, shorter;
            # k1 still holds f(t, x), so only the stages are redone
            h *= 0.25
            retries += 1
            continue
        retries = 0
        _switch(t_next, xn, c, G, P, f1, aux, g1)
        evals += 1
        if _changed(g1, g0):
            s, e = _cross(t, x, h, t_next, c, G, P, W, V, aux)
            evals += e
            if events < log_cap:
                log[(log_at + events) % log.size] = t + s
            events += 1
        steps += 1
        t = t_next
        for i in range(n):
            x[i] = xn[i]
            k1[i] = f1[i]
        for i in range(g0.size):
            g0[i] = g1[i]
        status = _after_step(t, x, c, P, Q)
        if status != STATUS_OK:
            return status, steps, events, evals, t, 0.0
    return STATUS_OK, steps, events, evals, t, 0.0


#: how often a step is retried shorter (each a quarter of the last) before it is taken anyway
#: and the state's own checks judge it
MAX_RETRIES = 6


@jit_noalloc
def _step_kept(x, xn, c, P):
    """False when the step from x to xn outran the step rule's estimate at its start and is
    retried shorter: level 1's lagged sag moved by more than a factor of two
    (:func:`chainmodel.kernels.spans.lag_step_kept`)."""
    return lag_step_kept(x, xn, P)


@jit_noalloc
def _omega_at(t, x, aux, c, G, P, Q):
    """The frequency of the step rule at (t, x), whose evaluation is in ``aux``."""
    return omega_estimate(aux, G, P, Q)


@jit_noalloc
def _event_step(c, Q):
    """A quarter tooth period at the larger input speed of the communication step's ends."""
    speed = max(abs(c[C_W0]), abs(c[C_W1]))
    return Q[Q_EVENT_ANGLE] / speed if speed > 0.0 else math.inf


@jit_noalloc
def _after_step(t, x, c, P, Q):
    """STATUS_NONFINITE when the state after a step is not finite, else :func:`_check`'s status
    (a span mode's amplitude beyond the string model, a lagged sag tension not positive): every
    step, as the plain loop's ``model.check``, so a state that leaves the model's range between
    two communication points is caught there too (level 2 at 50 ms communication steps
    otherwise passed through it and returned a state its 0.1 ms run refuses)."""
    for i in range(x.size):
        if not math.isfinite(x[i]):
            return STATUS_NONFINITE
    return _check(x, P, Q)


@jit_noalloc
def fill_outputs(x, aux, w_in, P, Q, out):
    """The 15 outputs (ALL_OUTPUTS order) from the state x and the kernel's evaluation ``aux``
    there; w_in the input-shaft speed. The tight span is the one the driver pulls for the
    direction of the transmitted torque (chainmodel.kernels.span_roles, decided in the kernel's
    evaluation from the inputs: aux[A_LOWER_TIGHT]), not the one with the larger tension at
    this instant. The reported span and link tensions include the centrifugal tension
    rho A v^2 = Q[Q_CENTRIFUGAL] w1^2 (chainmodel.models.base.centrifugal_tension); the sag and
    the seat force use the effective tension without it
    (chainmodel.models.base.quasi_static_extras). Level 1's midspan deflection is the
    quasi-static sag of the tight span under gravity, level 2's the span modes at the middle."""
    if P[P_RIGID] > 0.5:
        phi2 = x[0]
        w2 = x[1]
    else:
        phi2 = x[1]
        w2 = x[3]
    phi1 = aux[A_PHI1]
    w1 = aux[A_W1]
    t_up = aux[A_T_UP]
    t_low = aux[A_T_LOW]
    upper = aux[A_LOWER_TIGHT] < 0.5
    if upper:
        tight = t_up
        slack = t_low
        length = aux[A_L_UP]
    else:
        tight = t_low
        slack = t_up
        length = aux[A_L_LOW]
    centrifugal = Q[Q_CENTRIFUGAL] * w1 * w1
    ratio = Q[Q_RATIO]
    out[O_DRIVER_ANGLE] = phi1
    out[O_DRIVER_SPEED] = w1
    out[O_DRIVEN_ANGLE] = phi2
    out[O_DRIVEN_SPEED] = w2
    out[O_DRIVEN_ACCELERATION] = aux[A_ACC2]
    out[O_INPUT_SHAFT_TORQUE] = aux[A_TAU_IN]
    out[O_TIGHT_SPAN_TENSION] = tight + centrifugal
    out[O_SLACK_SPAN_TENSION] = slack + centrifugal
    out[O_TIGHT_SPAN_LENGTH] = length
    # at rest the instantaneous ratio is undefined; report the mean (tooth) ratio
    out[O_VELOCITY_RATIO] = w2 / w1 if abs(w1) > 1e-9 else ratio
    out[O_TRANSMISSION_ERROR] = phi2 - ratio * phi1
    if int(P[P_MODES]) > 0:
        out[O_TIGHT_SPAN_MIDSPAN_DEFLECTION] = aux[A_MID_UP] if upper else aux[A_MID_LOW]
    elif tight > 0.0:
        out[O_TIGHT_SPAN_MIDSPAN_DEFLECTION] = -min(Q[Q_SAG] * length * length / tight, 0.5 * length)
    else:
        out[O_TIGHT_SPAN_MIDSPAN_DEFLECTION] = -0.5 * length
    out[O_CHAIN_MAX_LINK_TENSION] = max(tight, slack) + centrifugal
    out[O_CONTACT_MAX_FORCE] = tight
    out[O_CHAIN_MIN_LINK_TENSION] = min(tight, slack) + centrifugal


@jit_noalloc
def outputs_into(x, th, w, acc, load, G, P, Q, dx, aux, out):
    """Every output at (x, inputs) into ``out`` (one kernel evaluation); True when all are
    finite."""
    evaluate(x, th, w, acc, load, G, P, dx, aux)
    fill_outputs(x, aux, w, P, Q, out)
    return finite(out)


@jit
def outputs_many(X, th, w, acc, load, G, P, Q, OUT):
    """:func:`outputs_into` for every row of X (inputs per row) into the rows of OUT."""
    dx = np.empty(X.shape[1])
    aux = np.empty(A_SIZE)
    for i in range(X.shape[0]):
        outputs_into(X[i], th[i], w[i], acc[i], load[i], G, P, Q, dx, aux, OUT[i])


@jit_noalloc
def _check(x, P, Q):
    """STATUS_AMPLITUDE when a span mode's amplitude exceeds Q_AMP_LIMIT (ModalModel.check);
    STATUS_NONFINITE when level 1's lagged sag tension is not positive (TorsionalModel.check:
    its sag term k S / T_q^2 is then meaningless)."""
    if P[P_LAG] > 0.5:
        k = lag_index(P)
        if not (x[k] > 0.0 and x[k + 1] > 0.0):
            return STATUS_NONFINITE
    n = int(P[P_MODES])
    if n > 0:
        base = 2 if P[P_RIGID] > 0.5 else 4
        for i in range(base, base + 2 * n):
            if abs(x[i]) > Q[Q_AMP_LIMIT]:
                return STATUS_AMPLITUDE
    return STATUS_OK


@jit
def _begin(K, n):
    """The work arrays of :func:`_advance`: the inputs c, the state-sized rows W, the switching
    functions' rows V, the kernel's auxiliary values and a flag ``started`` (W[3], V[0] and
    aux hold the evaluation at the current point with its own inputs), all in one allocation
    (the FMU's held step makes them at every communication step)."""
    w_end = C_SIZE + 1 + W_ROWS * n
    v_end = w_end + V_ROWS * 6
    buf = np.empty(v_end + A_SIZE)
    buf[C_SIZE] = 0.0
    buf[C_SEG_END] = -1.0
    buf[C_SEG_BLOCK] = -1.0
    return (buf[:C_SIZE], buf[C_SIZE + 1:w_end].reshape((W_ROWS, n)),
            buf[w_end:v_end].reshape((V_ROWS, 6)), buf[v_end:], buf[C_SIZE:C_SIZE + 1])


#: relative difference under which an interior point's inputs lie on the cubic through the
#: ends of a span of points (round-off of the Hermite form is about 1e-16)
SPAN_INPUT_TOL = 1e-12


@jit_noalloc
def _on_one_cubic(i, j, times, angle, speed, acc, load, c):
    """Whether the inputs given at points i .. j-1 lie on the interpolant ``c`` set for
    [times[i-1], times[j]] (:func:`_inputs`): then one step over the span sees the inputs the
    steps point by point would see."""
    for m in range(i, j):
        th, w, a, ld = _inputs(times[m], c)
        if (abs(th - angle[m]) > SPAN_INPUT_TOL * (1.0 + abs(angle[m]))
                or abs(w - speed[m]) > SPAN_INPUT_TOL * (1.0 + abs(speed[m]))
                or abs(a - acc[m]) > SPAN_INPUT_TOL * (1.0 + abs(acc[m]))
                or abs(ld - load[m]) > SPAN_INPUT_TOL * (1.0 + abs(load[m]))):
            return False
    return True


@jit_noalloc
def _set_interval(c, times, angle, speed, acc, load, a, b):
    """The interpolant of the inputs over [times[a], times[b]] into ``c``."""
    c[C_T0] = times[a]
    c[C_DT] = times[b] - times[a]
    c[C_A0] = angle[a]
    c[C_W0] = speed[a]
    c[C_A1] = angle[b]
    c[C_W1] = speed[b]
    c[C_ACC0] = acc[a]
    c[C_ACC1] = acc[b]
    c[C_L0] = load[a]
    c[C_L1] = load[b]
    c[C_IN_T] = math.nan        # a new interpolant: nothing evaluated on it yet


@jit_noalloc
def _span_step(i, x, times, angle, speed, acc, load, G, P, Q, cfg, c, W, V, aux):
    """One step from point i-1 over several communication points, where the automatic step
    bound exceeds two of their intervals (module docstring, "Steps spanning points"): the step
    to the last point j within the bound whose inputs at the points between lie on one cubic,
    kept when no switching function changes sign over it, the state stays finite and the
    step is within the bound at its end too. Kept: its ends (state, derivative) go to W[14-17]
    and c[C_SEG_*], and the points up to j take the step's dense output. Returns (kept, the
    evaluations made); ``aux`` is left stale either way."""
    n = times.size
    if cfg[CF_STEP] > 0.0 or i + 1 >= n or i <= c[C_SEG_BLOCK]:
        return False, 0
    t0 = times[i - 1]
    w = _omega_at(t0, x, aux, c, G, P, Q)
    top = max(abs(speed[i - 1]), abs(speed[i]))
    j = i
    while j + 1 < n:
        top = max(top, abs(speed[j + 1]))
        h_event = Q[Q_EVENT_ANGLE] / top if top > 0.0 else math.inf
        if times[j + 1] - t0 > _step_bound(w, h_event, cfg):
            break
        j += 1
    if j < i + 1:
        return False, 0
    _set_interval(c, times, angle, speed, acc, load, i - 1, j)
    if not _on_one_cubic(i, j, times, angle, speed, acc, load, c):
        c[C_SEG_BLOCK] = j
        return False, 0
    k1 = W[3]
    xn = W[0]
    f1 = W[8]
    made = 0
    for _attempt in range(2):
        h = times[j] - t0
        made += _step_from(t0, x, h, c, G, P, k1, W[4], W[5], W[6], W[7], aux, xn) + 1
        _switch(times[j], xn, c, G, P, f1, aux, V[1])
        if (_after_step(times[j], xn, c, P, Q) != STATUS_OK or not _step_kept(x, xn, c, P)
                or h > _step_bound(_omega_at(times[j], xn, aux, c, G, P, Q),
                                   _event_step(c, Q), cfg)):
            c[C_SEG_BLOCK] = j
            return False, made
        if not _changed(V[1], V[0]):
            break
        # an event inside: once more, to the last point before its secant estimate (with a
        # margin); else the points step one by one past the estimate (where the event
        # crossing of _interval takes it)
        s_cross = _secant(0.0, h, V[0], V[1], V[0])
        past = j
        while past > i and times[past - 1] >= t0 + s_cross:
            past -= 1
        while j > i and times[j] >= t0 + 0.8 * s_cross:
            j -= 1
        if _attempt == 1 or j < i + 1:
            c[C_SEG_BLOCK] = past
            return False, made
        _set_interval(c, times, angle, speed, acc, load, i - 1, j)
    for k in range(x.size):
        W[14, k] = x[k]
        W[15, k] = k1[k]
        W[16, k] = xn[k]
        W[17, k] = f1[k]
    c[C_SEG_T0] = t0
    c[C_SEG_H] = h
    c[C_SEG_END] = j
    return True, made


@jit_inline
def _advance(i, x, times, angle, speed, acc, load, K, cfg, S, log, logged, log_cap):
    """Communication step i of :func:`stepping.points`: :func:`_interval` on the cubic Hermite
    of the inputs at both ends (which checks every step's state); or, inside a step spanning
    several points (:func:`_span_step`), that step's dense output at the point."""
    G, P, Q = K
    c, W, V, aux, flags = S
    steps = 0
    made = 0
    if (c[C_SEG_END] < i and flags[0] != 0.0 and i + 1 < times.size and P[P_MODES] == 0.0
            and (times[i + 1] - times[i - 1]) * Q[Q_W_SPROCKET] <= cfg[CF_THETA]):
        # level 1 (level 2: module docstring), the evaluation at point i-1 (aux, W[3], V[0])
        # at its own inputs, and the tolerance's step on the sprockets' bound spanning two
        # intervals (the cheap test that keeps a drive whose bound is below them from paying
        # for the call): try a step spanning several points from there
        kept, made = _span_step(i, x, times, angle, speed, acc, load, G, P, Q, cfg, c, W, V, aux)
        if kept:
            steps = 1
        elif made > 0:
            flags[0] = 0.0          # aux is stale: the step below evaluates at its start again
    if c[C_SEG_END] >= i:
        if i == int(c[C_SEG_END]):
            for k in range(x.size):
                x[k] = W[16, k]
            c[C_SEG_END] = -1.0
        else:
            _dense(W[14], W[15], W[16], W[17], c[C_SEG_H], times[i] - c[C_SEG_T0], x)
        flags[0] = 0.0              # the outputs evaluate at the point's own inputs
        return _check(x, P, Q), steps, 0, made, times[i], 0.0
    t0 = times[i - 1]
    t1 = times[i]
    _set_interval(c, times, angle, speed, acc, load, i - 1, i)
    started = flags[0] != 0.0
    if started:
        # the evaluation that ended the last step was made at this point's own inputs;
        # it starts this step if the interpolant starts from the same ones (held or
        # constant acceleration): an evaluation is a pure function of (x, inputs)
        th, ww, aa, ld = _inputs(t0, c)
        started = (th == angle[i - 1] and ww == speed[i - 1] and aa == acc[i - 1]
                   and ld == load[i - 1])
    status, m, e, v, t_st, w = _interval(x, t0, t1, c, G, P, Q, cfg, W, V, aux, log, logged,
                                        log_cap, started)
    v += made
    if status == STATUS_OK:          # _interval checked the state after its last step
        t_st = t1
        th, ww, aa, ld = _inputs_at(t1, c)     # the step end's, usually remembered
        started = th == angle[i] and ww == speed[i] and aa == acc[i] and ld == load[i]
        flags[0] = 1.0 if started else 0.0
    return status, m, e, v, t_st, w


@jit_inline
def _outputs(i, x, angle, speed, acc, load, K, S, out):
    """The outputs at point i into ``out``; returns the evaluations made (0 when the one that
    ended the last step was at the point's own inputs)."""
    G, P, Q = K
    c, W, V, aux, flags = S
    e = 0
    if flags[0] == 0.0:
        # the point's inputs differ from the interpolant's end values (a change of
        # acceleration, round-off of the load): evaluate at the point's own inputs,
        # which also starts the next step
        _switch_at(x, angle[i], speed[i], acc[i], load[i], G, P, W[3], aux, V[0])
        e = 1
        flags[0] = 1.0
    fill_outputs(x, aux, speed[i], P, Q, out)
    return e


@jit_noalloc
def _switch_at(x, th, w, acc, load, G, P, dx, aux, g):
    """:func:`_switch` at given inputs."""
    evaluate(x, th, w, acc, load, G, P, dx, aux)
    for i in range(6):
        g[i] = aux[A_G_UP + i]


#: the sampling loop and the held step, written once in chainmodel.kernels.stepping
_points = instance(stepping.points, "_points", __name__, _advance=_advance, _outputs=_outputs)
_held = instance(stepping.held, "_held", __name__, noalloc=False, _points=_points,
                 _begin=_begin)


@jit
def advance_points(x_in, x_out, times, angle, speed, acc, load, G, P, Q, cfg, OUT, states, log,
                   log_cap):
    """Integrate from (times[0], x_in) through the communication points ``times`` (inputs given
    there: angle, speed, acc, load; cubic Hermite inside each step, module docstring), leaving
    ``x_in`` untouched and the state at the last point reached in ``x_out``: this level's
    instance of :func:`chainmodel.kernels.stepping.points` (its docstring: OUT, states, log,
    the result). Status as :func:`_interval` (which checks the state after every step;
    :func:`_check` also at the points a step spanning several takes from its dense output) or
    STATUS_OUTPUTS."""
    K = (G, P, Q)
    return _points(x_in, x_out, times, angle, speed, acc, load, K, _begin(K, x_in.size), cfg, OUT,
                   states, log, log_cap)


@jit
def advance_held(x_in, x_out, t0, t1, a0, w0, acc, load, G, P, Q, cfg, OUT, log):
    """One communication step [t0, t1] with the inputs held first-order (the FMU's hold):
    this level's instance of :func:`chainmodel.kernels.stepping.held`; the outputs at t1 go to
    OUT[1] (OUT has two rows)."""
    return _held(x_in, x_out, t0, t1, a0, w0, acc, load, (G, P, Q), cfg, OUT, log)
