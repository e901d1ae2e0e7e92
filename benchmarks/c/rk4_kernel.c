/*
 * Plain C baseline of gearvib's run-up kernel (benchmarks only, not part of the package).
 *
 * The same algorithm as gearvib.kernels.integrate_chunk for models without tooth faults or
 * manufacturing errors: the right-hand side of the packed system (sparse operators
 * premultiplied by M^-1, drive (a coupling on the input member or a controller on the
 * rigid-body coordinate), load, gyroscopic terms, two-flank contact law with one or two
 * lines of action, gated or always-on (viscous) mesh damping per mesh), classical RK4 with sub-steps ending at the predicted stiffness jumps, and
 * the recorded sample rows. It reads the very arrays gearvib.kernels.pack builds and performs
 * the same floating-point operations in the same order, so its output is bit-identical to the
 * numba kernel's (benchmarks/bench_kernel.py checks this) and its time is the reference a
 * compiled loop of this algorithm can reach.
 *
 * Build: gcc -O2 -shared -fPIC (no -ffast-math, no -march: IEEE operations, no contraction).
 */
#include <math.h>
#include <stdint.h>

/* header of the packed integer array: mirrors gearvib/kernels.py (checked at run time) */
enum { H_N = 0, H_NMESH = 1, H_IPAR = 2 };
enum { IP_MODE = 0, IP_INPUT = 1, IP_OUTPUT = 2, IP_CARRIER = 3, IP_GYRO = 4, N_IPAR = 5 };
enum { FP_KC = 0, FP_CC = 1, FP_OUTDIR = 2, FP_T0 = 3, FP_C1 = 4, FP_C2 = 5, FP_SPEED_LIMIT = 6 };
enum {
    H_LP = H_IPAR + N_IPAR, H_LI, H_CP, H_CI, H_GP, H_GI, H_II, H_OI, H_VP, H_VI, H_FP, H_FI,
    H_PP, H_PI, H_BP, H_RFLAG, H_RVP, H_RVI, H_RFP, H_RFI, H_FREC, H_FINT, H_MLAW, H_DI,
    H_ACC0, H_LV, H_CV, H_GV, H_IV, H_OV, H_VV, H_FV, H_PV, H_S0, H_BL, H_MC, H_FPAR, H_LIMIT,
    H_BV, H_RVV, H_RFV, H_FVAL, H_DV, H_NI, H_NO, H_FPASS, H_ND, N_HEADER
};
enum { DRIVE_NONE = 0, DRIVE_SPEED = 1, DRIVE_TORQUE = 2, DRIVE_MOTOR = 3 };
enum { STATUS_OK = 0, STATUS_NONFINITE = 1, STATUS_DEFLECTION = 2, STATUS_SPEED = 3 };
#define MESH_OUT_COLUMNS 31 /* gearvib.kernels.MESH_OUT_COLUMNS (the first 7 are used) */

int64_t gv_header_size(void) { return N_HEADER; }

/* The header layout as this file sees it, in the order of HEADER_NAMES in
 * benchmarks/bench_kernel.py, which compares it with gearvib.kernels' constants. */
#define GV_LAYOUT                                                                           \
    H_N, H_NMESH, H_IPAR, IP_MODE, IP_INPUT, IP_OUTPUT, IP_CARRIER, IP_GYRO, N_IPAR, FP_KC, \
        FP_CC, FP_OUTDIR, FP_T0, FP_C1, FP_C2, FP_SPEED_LIMIT, H_LP, H_LI, H_CP, H_CI,      \
        H_GP, H_GI, H_II, H_OI, H_VP, H_VI, H_FP, H_FI, H_PP, H_PI, H_BP, H_RFLAG, H_RVP,   \
        H_RVI, H_RFP, H_RFI, H_FREC, H_FINT, H_MLAW, H_DI, H_ACC0, H_LV, H_CV, H_GV, H_IV,  \
        H_OV, H_VV, H_FV, H_PV, H_S0, H_BL, H_MC, H_FPAR, H_LIMIT, H_BV, H_RVV, H_RFV,      \
        H_FVAL, H_DV, H_NI, H_NO, H_FPASS, H_ND, N_HEADER, DRIVE_NONE, DRIVE_SPEED,         \
        DRIVE_TORQUE, DRIVE_MOTOR, MESH_OUT_COLUMNS
static const int64_t gv_layout[] = {GV_LAYOUT};

int64_t gv_header_layout(int64_t *out, int64_t cap)
{
    int64_t n = (int64_t)(sizeof gv_layout / sizeof gv_layout[0]);
    for (int64_t k = 0; k < n && k < cap; k++)
        out[k] = gv_layout[k];
    return n;
}

typedef struct {
    const int64_t *ints;
    const double *vals;
    const double *tables; /* (2, n_mesh, n_table) */
    int64_t n_table;
    const double *speed; /* (3, n_speed) */
    int64_t n_speed;
    const double *torque; /* (2, n_torque) */
    int64_t n_torque;
} gv_system;

static int64_t segment(const double *tt, int64_t n, double t)
{
    int64_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        int64_t mid = (lo + hi) / 2;
        if (tt[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

static void speed_at(const double *tab, int64_t n, double t, double *phi_out, double *w_out)
{
    const double *tt = tab, *w = tab + n, *phi = tab + 2 * n;
    if (n == 1 || t <= tt[0]) {
        *phi_out = phi[0] + w[0] * (t - tt[0]);
        *w_out = w[0];
        return;
    }
    if (t >= tt[n - 1]) {
        *phi_out = phi[n - 1] + w[n - 1] * (t - tt[n - 1]);
        *w_out = w[n - 1];
        return;
    }
    int64_t i = segment(tt, n, t);
    double tau = t - tt[i];
    double slope = (w[i + 1] - w[i]) / (tt[i + 1] - tt[i]);
    *phi_out = phi[i] + w[i] * tau + 0.5 * slope * tau * tau;
    *w_out = w[i] + slope * tau;
}

static double table_at(const double *tab, int64_t n, double t)
{
    const double *tt = tab, *v = tab + n;
    if (n == 1 || t <= tt[0])
        return v[0];
    if (t >= tt[n - 1])
        return v[n - 1];
    int64_t i = segment(tt, n, t);
    return v[i] + (v[i + 1] - v[i]) * (t - tt[i]) / (tt[i + 1] - tt[i]);
}

static void rhs(double t, const double *y, double *dy, double *mesh_out, const gv_system *sys)
{
    const int64_t *ints = sys->ints;
    const double *vals = sys->vals;
    const int64_t n = ints[H_N], n_mesh = ints[H_NMESH], n_table = sys->n_table;
    const int64_t lp = ints[H_LP], li = ints[H_LI], lv = ints[H_LV], a0 = ints[H_ACC0];
    for (int64_t i = 0; i < n; i++) {
        dy[i] = y[n + i];
        double acc = vals[a0 + i];
        for (int64_t p = ints[lp + i]; p < ints[lp + i + 1]; p++)
            acc += vals[lv + p] * y[ints[li + p]];
        dy[n + i] = acc;
    }
    const int64_t fpar = ints[H_FPAR];
    const int64_t carrier = ints[H_IPAR + IP_CARRIER];
    if (ints[H_IPAR + IP_GYRO] != 0 && carrier >= 0) {
        double om = y[n + carrier];
        double om2 = om * om;
        const int64_t cp = ints[H_CP], ci = ints[H_CI], cv = ints[H_CV];
        const int64_t gp = ints[H_GP], gi = ints[H_GI], gv = ints[H_GV];
        for (int64_t i = 0; i < n; i++) {
            double acc = 0.0;
            for (int64_t p = ints[cp + i]; p < ints[cp + i + 1]; p++)
                acc += vals[cv + p] * y[ints[ci + p]];
            double acc2 = 0.0;
            for (int64_t p = ints[gp + i]; p < ints[gp + i + 1]; p++)
                acc2 += vals[gv + p] * y[n + ints[gi + p]];
            dy[n + i] += om2 * acc + om * acc2;
        }
    }
    const int64_t mode = ints[H_IPAR + IP_MODE];
    const int64_t k_in = ints[H_IPAR + IP_INPUT];
    double torque = 0.0;
    if (mode == DRIVE_SPEED) {
        double phi, w;
        speed_at(sys->speed, sys->n_speed, t, &phi, &w);
        const int64_t nd = ints[H_ND];
        if (nd == 0) { /* a coupling on the input coordinate */
            torque = vals[fpar + FP_KC] * (phi - y[k_in]) + vals[fpar + FP_CC] * (w - y[n + k_in]);
        } else { /* a controller on the rigid-body coordinate p . q */
            const int64_t di = ints[H_DI], dv = ints[H_DV];
            double ang = 0.0, rate = 0.0;
            for (int64_t p = 0; p < nd; p++) {
                int64_t j = ints[di + p];
                ang += vals[dv + p] * y[j];
                rate += vals[dv + p] * y[n + j];
            }
            torque = vals[fpar + FP_KC] * (phi - ang) + vals[fpar + FP_CC] * (w - rate);
        }
    } else if (mode == DRIVE_TORQUE) {
        torque = table_at(sys->torque, sys->n_torque, t);
    } else if (mode == DRIVE_MOTOR) {
        torque = table_at(sys->torque, sys->n_torque, y[n + k_in]);
    }
    if (torque != 0.0) {
        const int64_t ii = ints[H_II], iv = ints[H_IV];
        for (int64_t p = 0; p < ints[H_NI]; p++)
            dy[n + ints[ii + p]] += vals[iv + p] * torque;
    }
    const int64_t k_out = ints[H_IPAR + IP_OUTPUT];
    if (k_out >= 0) {
        double e = vals[fpar + FP_OUTDIR];
        double wo = e * y[n + k_out];
        double load = -e * (vals[fpar + FP_T0] + vals[fpar + FP_C1] * wo
                            + vals[fpar + FP_C2] * wo * fabs(wo));
        const int64_t oi = ints[H_OI], ov = ints[H_OV];
        for (int64_t p = 0; p < ints[H_NO]; p++)
            dy[n + ints[oi + p]] += vals[ov + p] * load;
    }
    const int64_t vp = ints[H_VP], vi = ints[H_VI], vv = ints[H_VV];
    const int64_t fp = ints[H_FP], fi = ints[H_FI], fv = ints[H_FV];
    const int64_t pp = ints[H_PP], pi = ints[H_PI], pv = ints[H_PV];
    const int64_t s0 = ints[H_S0], bl = ints[H_BL], mc = ints[H_MC], rflag = ints[H_RFLAG];
    const int64_t rvp = ints[H_RVP], rvi = ints[H_RVI], rvv = ints[H_RVV];
    const int64_t rfp = ints[H_RFP], rfi = ints[H_RFI], rfv = ints[H_RFV];
    const int64_t mlaw = ints[H_MLAW];
    const double *tl = sys->tables, *tr = sys->tables + n_mesh * n_table;
    for (int64_t m = 0; m < n_mesh; m++) {
        double d = 0.0, dd = 0.0;
        for (int64_t p = ints[vp + m]; p < ints[vp + m + 1]; p++) {
            int64_t j = ints[vi + p];
            d += vals[vv + p] * y[j];
            dd += vals[vv + p] * y[n + j];
        }
        int two_lines = ints[rflag + m] != 0;
        double dr = d, ddr = dd;
        if (two_lines) {
            dr = 0.0;
            ddr = 0.0;
            for (int64_t p = ints[rvp + m]; p < ints[rvp + m + 1]; p++) {
                int64_t j = ints[rvi + p];
                dr += vals[rvv + p] * y[j];
                ddr += vals[rvv + p] * y[n + j];
            }
        }
        double s = vals[s0 + m];
        for (int64_t p = ints[pp + m]; p < ints[pp + m + 1]; p++)
            s += vals[pv + p] * y[ints[pi + p]];
        /* periodic linear interpolation of the flank tables */
        double frac = s - floor(s);
        double u = frac * (double)n_table;
        int64_t i0 = (int64_t)u;
        double w = u - (double)i0;
        if (i0 >= n_table) {
            i0 = 0;
            w = 0.0;
        }
        int64_t i1 = i0 + 1;
        if (i1 == n_table)
            i1 = 0;
        double kl = (1.0 - w) * tl[m * n_table + i0] + w * tl[m * n_table + i1];
        double kr = (1.0 - w) * tr[m * n_table + i0] + w * tr[m * n_table + i1];
        /* contact law of both flanks (paper eq. 2) */
        double backlash = vals[bl + m], damping = vals[mc + m];
        double half = 0.5 * backlash;
        double fl = 0.0, fr = 0.0, ke = 0.0;
        int64_t st = 0;
        if (ints[mlaw + m] != 0) { /* always-on (viscous) damping, flank_forces_viscous */
            if (d > half) {
                fl = kl * (d - half);
                ke += kl;
                st += 1;
            }
            if (dr < -half) {
                fr = kr * (dr + half);
                ke += kr;
                st += 2;
            }
            if (st == 2)
                fr += damping * ddr;
            else
                fl += damping * dd;
        } else { /* gated damping, flank_forces_two_lines */
            if (d > half) {
                fl = kl * (d - half) + damping * dd;
                if (fl < 0.0)
                    fl = 0.0;
                ke += kl;
                st += 1;
            }
            if (dr < -half) {
                fr = kr * (dr + half) + damping * ddr;
                if (fr > 0.0)
                    fr = 0.0;
                ke += kr;
                st += 2;
            }
        }
        if (two_lines) {
            if (fl != 0.0)
                for (int64_t p = ints[fp + m]; p < ints[fp + m + 1]; p++)
                    dy[n + ints[fi + p]] -= fl * vals[fv + p];
            if (fr != 0.0)
                for (int64_t p = ints[rfp + m]; p < ints[rfp + m + 1]; p++)
                    dy[n + ints[rfi + p]] -= fr * vals[rfv + p];
        } else {
            double f = fl + fr;
            if (f != 0.0)
                for (int64_t p = ints[fp + m]; p < ints[fp + m + 1]; p++)
                    dy[n + ints[fi + p]] -= f * vals[fv + p];
        }
        double *mo = mesh_out + m * MESH_OUT_COLUMNS;
        mo[0] = fl;
        mo[1] = -fr;
        mo[2] = ke;
        mo[3] = (double)st;
        mo[4] = d;
        mo[5] = s;
        mo[6] = dr;
    }
}

static int64_t insert_split(double *splits, int64_t cap, int64_t count, double tau, double dt,
                            double tol)
{
    if (!(tol < tau && tau < dt - tol))
        return count;
    int64_t j = count;
    while (j > 0 && splits[j - 1] > tau)
        j--;
    if ((j > 0 && tau - splits[j - 1] <= tol) || (j < count && splits[j] - tau <= tol))
        return count;
    if (count == cap)
        return count;
    for (int64_t r = count; r > j; r--)
        splits[r] = splits[r - 1];
    splits[j] = tau;
    return count + 1;
}

static int64_t split_times(const double *y, double dt, const gv_system *sys,
                           const double *mesh_out, double *splits, int64_t cap)
{
    const int64_t *ints = sys->ints;
    const double *vals = sys->vals;
    const int64_t n = ints[H_N];
    const int64_t pp = ints[H_PP], pi = ints[H_PI], pv = ints[H_PV];
    const int64_t bp = ints[H_BP], bv = ints[H_BV];
    const double tol = 1e-9 * dt;
    int64_t count = 0;
    for (int64_t m = 0; m < ints[H_NMESH]; m++) {
        int64_t b0 = ints[bp + m], b1 = ints[bp + m + 1];
        if (b1 == b0)
            continue;
        double s = mesh_out[m * MESH_OUT_COLUMNS + 5];
        double sd = 0.0;
        for (int64_t p = ints[pp + m]; p < ints[pp + m + 1]; p++)
            sd += vals[pv + p] * y[n + ints[pi + p]];
        double s_end = s + sd * dt;
        double lo = s < s_end ? s : s_end; /* min/max as numba's (no NaN here) */
        double hi = s > s_end ? s : s_end;
        if (sd == 0.0)
            continue;
        double base = floor(lo);
        int64_t nk = (int64_t)(floor(hi) - base) + 1;
        for (int64_t k = 0; k < nk; k++)
            for (int64_t q = b0; q < b1; q++) {
                double tau = (base + (double)k + vals[bv + q] - s) / sd;
                count = insert_split(splits, cap, count, tau, dt, tol);
            }
    }
    return count;
}

static void rk4_step(double t, double h, double *y, double *k1, double *k2, double *k3,
                     double *k4, double *tmp, double *mesh_out, const gv_system *sys)
{
    const int64_t n2 = 2 * sys->ints[H_N];
    double h2 = 0.5 * h, h6 = h / 6.0;
    for (int64_t i = 0; i < n2; i++)
        tmp[i] = y[i] + h2 * k1[i];
    rhs(t + h2, tmp, k2, mesh_out, sys);
    for (int64_t i = 0; i < n2; i++)
        tmp[i] = y[i] + h2 * k2[i];
    rhs(t + h2, tmp, k3, mesh_out, sys);
    for (int64_t i = 0; i < n2; i++)
        tmp[i] = y[i] + h * k3[i];
    rhs(t + h, tmp, k4, mesh_out, sys);
    for (int64_t i = 0; i < n2; i++)
        y[i] += h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
}

/*
 * integrate_chunk of gearvib.kernels for a model without faults (every fault record -1).
 * Returns the number of right-hand-side evaluations; status as the numba kernel's.
 */
int64_t gv_integrate_chunk(const int64_t *ints, const double *vals, const double *tables,
                           int64_t n_table, const double *speed, int64_t n_speed,
                           const double *torque, int64_t n_torque, double *y, int64_t first_step,
                           int64_t n_steps, double dt, double *record, int64_t n_col,
                           int64_t record_offset, int64_t *flank_state, int64_t *contact_changes,
                           int64_t count_until, double *work, int64_t work_cols,
                           double *mesh_out, int64_t *status)
{
    gv_system sys = {ints, vals, tables, n_table, speed, n_speed, torque, n_torque};
    const int64_t n = ints[H_N], n_mesh = ints[H_NMESH];
    const int64_t lim = ints[H_LIMIT];
    const double speed_limit = vals[ints[H_FPAR] + FP_SPEED_LIMIT];
    const int64_t k_in = ints[H_IPAR + IP_INPUT];
    double *k1 = work, *k2 = work + work_cols, *k3 = work + 2 * work_cols;
    double *k4 = work + 3 * work_cols, *tmp = work + 4 * work_cols, *splits = work + 5 * work_cols;
    const int64_t n2 = 2 * n;
    int64_t n_rhs = 0;
    status[0] = STATUS_OK;
    status[1] = first_step + n_steps;
    for (int64_t step = 0; step < n_steps; step++) {
        int64_t g = first_step + step;
        double t = (double)g * dt;
        rhs(t, y, k1, mesh_out, &sys);
        n_rhs++;
        double *row = record + (record_offset + step) * n_col;
        int64_t bad = STATUS_OK;
        for (int64_t i = 0; i < n2; i++) {
            double v = y[i];
            row[i] = v;
            if (!isfinite(v))
                bad = STATUS_NONFINITE;
        }
        for (int64_t m = 0; m < n_mesh; m++) {
            const double *mo = mesh_out + m * MESH_OUT_COLUMNS;
            row[n2 + m] = mo[0];
            row[n2 + n_mesh + m] = mo[1];
            row[n2 + 2 * n_mesh + m] = mo[2];
            int64_t st = (int64_t)mo[3];
            if (flank_state[m] >= 0 && st != flank_state[m] && g <= count_until)
                contact_changes[m] += 1;
            flank_state[m] = st;
            if (bad == STATUS_OK && !(fabs(mo[4]) <= vals[lim + m] && fabs(mo[6]) <= vals[lim + m]))
                bad = STATUS_DEFLECTION;
        }
        if (bad == STATUS_OK && k_in >= 0 && !(fabs(y[n + k_in]) <= speed_limit))
            bad = STATUS_SPEED;
        if (bad != STATUS_OK) {
            status[0] = bad;
            status[1] = g;
            return n_rhs;
        }
        int64_t n_split = split_times(y, dt, &sys, mesh_out, splits, work_cols);
        double t_a = 0.0;
        for (int64_t j = 0; j < n_split + 1; j++) {
            double t_b = j < n_split ? splits[j] : dt;
            if (j > 0) {
                rhs(t + t_a, y, k1, mesh_out, &sys);
                n_rhs++;
            }
            rk4_step(t + t_a, t_b - t_a, y, k1, k2, k3, k4, tmp, mesh_out, &sys);
            n_rhs += 3;
            t_a = t_b;
        }
    }
    return n_rhs;
}

/* n_eval right-hand sides at the states of `states` (n_state rows, cycled); for timing. */
double gv_rhs_loop(const int64_t *ints, const double *vals, const double *tables,
                   int64_t n_table, const double *speed, int64_t n_speed, const double *torque,
                   int64_t n_torque, const double *states, int64_t n_state, double t0, double dt,
                   int64_t n_eval, double *dy, double *mesh_out)
{
    gv_system sys = {ints, vals, tables, n_table, speed, n_speed, torque, n_torque};
    const int64_t n2 = 2 * ints[H_N];
    double check = 0.0;
    int64_t r = 0;
    for (int64_t k = 0; k < n_eval; k++) {
        rhs(t0 + (double)r * dt, states + r * n2, dy, mesh_out, &sys);
        check += dy[n2 - 1];
        r++;
        if (r == n_state)
            r = 0;
    }
    return check;
}
