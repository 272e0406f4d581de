/* The compiled C floor of the level-3 (multibody) model: the force law of
 * chainmodel/kernels/multibody_forces.py (accelerations) and its velocity-Verlet loop
 * (kernels/multibody_loops.py fixed_steps, method 0), written in plain C, line for line, for
 * benchmarks/level3_floor.py, which compiles it with gcc and times it against the
 * library in the same run. The parameter vector P has the layout of kernels/multibody_layout.py
 * (PARAM_FIELDS, then the seat-direction tables); its indices come from floor_params.h, which
 * the benchmark writes from PARAM_FIELDS. Inputs: the input shaft turning at a constant speed
 * (angle w t, speed w, acceleration 0) against a constant load - the steady running of the
 * benchmark's scenes. Not part of the package. */
#include <math.h>
#include <stdlib.h>
#include "floor_params.h"

typedef struct {
    double *tension, *fcon, *scr, *dist, *seat_angle;
    int *side;
} work_t;

static int accel(int n, const double *q, const double *v, double tau, double tau_d,
                 double tau_dd, double load, const double *P, double *a, work_t *W,
                 double *shaft_out)
{
    int M = (n - 2) / 2;
    double m = P[I_M], k = P[I_K], c = P[I_C], l0 = P[I_L0], kc = P[I_KC], cc = P[I_CC];
    double dR = P[I_DR];
    int paper_contact = P[I_PAPER_CONTACT] != 0.0, paper_damp = P[I_PAPER_DAMP] != 0.0;
    int rigid = P[I_RIGID] != 0.0;
    double lmin = P[I_LMIN], lmax = P[I_LMAX];
    double phi1 = rigid ? tau : q[0], w1 = rigid ? tau_d : v[0];
    double phi2 = q[1], w2 = v[1];
    int status = 0;
    double gap = P[I_GAP], onset = P[I_ONSET];
    for (int i = 2; i < n; i++) a[i] = 0.0;
    for (int i = 0; i < M; i++) {
        int j = i + 1 == M ? 0 : i + 1;
        double dx = q[2 + 2 * j] - q[2 + 2 * i], dy = q[3 + 2 * j] - q[3 + 2 * i];
        double L = sqrt(dx * dx + dy * dy);
        if (!(L > lmin && L < lmax)) { status = 1; if (!(L > 0.0)) L = 1e-300; }
        double ex = dx / L, ey = dy / L;
        double dvx = v[2 + 2 * j] - v[2 + 2 * i], dvy = v[3 + 2 * j] - v[3 + 2 * i];
        double rate = ex * dvx + ey * dvy, e = L - l0, Ts, T, cl, fx, fy;
        if (e > 0.0) {
            Ts = k * e; cl = e >= onset ? c : c * e / onset; T = Ts + cl * rate;
            if (T < 0.0) T = 0.0;
        } else if (e < -gap) {
            Ts = k * (e + gap); cl = -gap - e >= onset ? c : c * (-gap - e) / onset;
            T = Ts + cl * rate;
            if (T > 0.0) T = 0.0;
        } else { Ts = 0.0; T = 0.0; cl = 0.0; }
        if (paper_damp) { fx = Ts * ex + cl * dvx; fy = Ts * ey + cl * dvy; W->tension[i] = Ts + cl * rate; }
        else { fx = T * ex; fy = T * ey; W->tension[i] = T; }
        a[2 + 2 * i] += fx; a[3 + 2 * i] += fy; a[2 + 2 * j] -= fx; a[3 + 2 * j] -= fy;
        W->scr[i] = (dx * dvy - dy * dvx) / (L * L);
    }
    double cj = P[I_CJ];
    if (cj > 0.0) {
        for (int i = 0; i < M; i++) {
            int j = i + 1 == M ? 0 : i + 1, im = i - 1 < 0 ? M - 1 : i - 1;
            double Tj = cj * (2.0 * W->scr[i] - W->scr[im] - W->scr[j]);
            double dx = q[2 + 2 * j] - q[2 + 2 * i], dy = q[3 + 2 * j] - q[3 + 2 * i];
            double L2 = dx * dx + dy * dy;
            if (!(L2 > 0.0)) L2 = 1e-300;
            double fx = -Tj * dy / L2, fy = Tj * dx / L2;
            a[2 + 2 * i] += fx; a[3 + 2 * i] += fy; a[2 + 2 * j] -= fx; a[3 + 2 * j] -= fy;
        }
    }
    double torque1 = 0.0, torque2 = 0.0;
    int z1 = (int)P[I_Z1], z2 = (int)P[I_Z2];
    double ph1 = P[I_PH1] - phi1, ph2 = P[I_PH2] - phi2;
    double cph1 = cos(ph1), sph1 = sin(ph1), cph2 = cos(ph2), sph2 = sin(ph2);
    for (int i = 0; i < M; i++) {
        double x = q[2 + 2 * i], y = q[3 + 2 * i], vx = v[2 + 2 * i], vy = v[3 + 2 * i];
        W->side[i] = 0; W->fcon[i] = 0.0;
        for (int s = 0; s < 2; s++) {
            double cx, cy, R, ph, cph, sph, ta, w, tip, sg, cg, reach; int zt, tab;
            if (s == 0) {
                cx = P[I_CX]; cy = P[I_CY]; R = P[I_R1]; ph = ph1; cph = cph1; sph = sph1;
                ta = P[I_TA1]; w = w1; tip = P[I_TIP1]; sg = P[I_SG1]; cg = P[I_CG1]; zt = z1;
                tab = N_PARAMS; reach = P[I_REACH1];
            } else {
                cx = 0.0; cy = 0.0; R = P[I_R2]; ph = ph2; cph = cph2; sph = sph2;
                ta = P[I_TA2]; w = w2; tip = P[I_TIP2]; sg = P[I_SG2]; cg = P[I_CG2]; zt = z2;
                tab = N_PARAMS + 2 * z1; reach = P[I_REACH2];
            }
            double rx = x - cx, ry = y - cy;
            if (rx * rx + ry * ry > reach * reach) {
                W->dist[s * M + i] = INFINITY; W->seat_angle[s * M + i] = 0.0; continue;
            }
            double jj = floor((atan2(ry, rx) - ph) / ta + 0.5);
            double th = ph + ta * jj;
            long jmi = (long)jj % zt; if (jmi < 0) jmi += zt;
            int jm = (int)jmi;
            double ct = cph * P[tab + jm] - sph * P[tab + zt + jm];
            double st = sph * P[tab + jm] + cph * P[tab + zt + jm];
            double dx = rx - R * ct, dy = ry - R * st, d = sqrt(dx * dx + dy * dy);
            W->dist[s * M + i] = d; W->seat_angle[s * M + i] = th;
            double pen = -1.0, nx = 0.0, ny = 0.0;
            if (paper_contact) {
                if (rx * rx + ry * ry <= R * R && d > dR) { pen = d - dR; nx = dx / d; ny = dy / d; }
            } else {
                double sl = dx * ct + dy * st;
                if (sl <= tip && d > 0.0) {
                    if (-sl >= d * cg) { pen = d - dR; nx = dx / d; ny = dy / d; }
                    else {
                        double tl = -dx * st + dy * ct, sgn = tl >= 0.0 ? 1.0 : -1.0;
                        pen = fabs(tl) * sg - sl * cg - dR;
                        nx = -sgn * sg * st - cg * ct; ny = sgn * sg * ct - cg * st;
                    }
                }
            }
            if (pen > 0.0) {
                double cross = rx * ny - ry * nx, Fn, fx, fy, tq;
                if (paper_damp) {
                    Fn = kc * pen;
                    double dvx = w * R * st - vx, dvy = -w * R * ct - vy;
                    fx = -Fn * nx + cc * dvx; fy = -Fn * ny + cc * dvy;
                    tq = -Fn * cross - cc * R * (dvx * st - dvy * ct);
                } else {
                    double pend = nx * (vx - w * ry) + ny * (vy + w * rx);
                    Fn = kc * pen + cc * pend;
                    if (Fn < 0.0) Fn = 0.0;
                    fx = -Fn * nx; fy = -Fn * ny; tq = -Fn * cross;
                }
                a[2 + 2 * i] += fx; a[3 + 2 * i] += fy;
                if (s == 0) torque1 += tq; else torque2 += tq;
                W->side[i] = s + 1; W->fcon[i] += Fn;
            }
        }
    }
    double shaft;
    if (rigid) { a[0] = tau_dd; shaft = P[I_I1] * tau_dd - torque1; }
    else { shaft = P[I_KR] * (tau - q[0]) + P[I_CR] * (tau_d - v[0]); a[0] = (shaft + torque1) / P[I_I1]; }
    a[1] = (torque2 - load - P[I_C2] * w2) / P[I_I2];
    double gx = P[I_GX] * m, gy = P[I_GY] * m;
    int qf = P[I_QF] != 0.0;
    for (int i = 0; i < M; i++) {
        double fx = gx, fy = gy;
        if (qf && W->side[i] > 0) {
            int s = W->side[i] - 1;
            double th = W->seat_angle[s * M + i], R, w, al;
            if (s == 0) { R = P[I_R1]; w = w1; al = a[0]; } else { R = P[I_R2]; w = w2; al = a[1]; }
            fx += m * R * (w * w * cos(th) - al * sin(th));
            fy += m * R * (w * w * sin(th) + al * cos(th));
        }
        a[2 + 2 * i] = (a[2 + 2 * i] + fx) / m;
        a[3 + 2 * i] = (a[3 + 2 * i] + fy) / m;
    }
    for (int i = 0; i < n; i++) if (!(a[i] - a[i] == 0.0)) status = 1;
    *shaft_out = shaft;
    return status;
}

/* nsteps velocity-Verlet steps of h from (t0, x) (x = [q, v], 2 n entries), in place; the
 * input shaft at angle w_in t, speed w_in. evals_per_step 2: the library's numbers (each step
 * starts with an evaluation at its own (q, v), and ends with one at the new positions and the
 * half-step velocity; the library gets them from one position pass and two velocity passes);
 * 1: the floor of issue 20 (the end evaluation also starts the next step). Returns -1, or the step after which the state diverged. */
long verlet(int n, double *x, double t0, double h, long nsteps, double w_in, double load,
            const double *P, int evals_per_step)
{
    int M = (n - 2) / 2;
    double *q = x, *v = x + n, shaft;
    double *acc = malloc(sizeof(double) * n), *acc2 = malloc(sizeof(double) * n);
    work_t W;
    W.tension = malloc(sizeof(double) * M); W.fcon = malloc(sizeof(double) * M);
    W.scr = malloc(sizeof(double) * M); W.dist = malloc(sizeof(double) * 2 * M);
    W.seat_angle = malloc(sizeof(double) * 2 * M); W.side = malloc(sizeof(int) * M);
    long bad = -1;
    accel(n, q, v, w_in * t0, w_in, 0.0, load, P, acc, &W, &shaft);
    for (long step = 0; step < nsteps; step++) {
        double t = t0 + step * h;
        if (evals_per_step == 2 && step > 0)
            accel(n, q, v, w_in * t, w_in, 0.0, load, P, acc, &W, &shaft);
        for (int i = 0; i < n; i++) {
            v[i] += 0.5 * h * acc[i];
            q[i] += h * v[i];
        }
        int st = accel(n, q, v, w_in * (t + h), w_in, 0.0, load, P, acc2, &W, &shaft);
        for (int i = 0; i < n; i++) { v[i] += 0.5 * h * acc2[i]; acc[i] = acc2[i]; }
        if (st) { bad = step; break; }
    }
    free(acc); free(acc2); free(W.tension); free(W.fcon); free(W.scr); free(W.dist);
    free(W.seat_angle); free(W.side);
    return bad;
}
