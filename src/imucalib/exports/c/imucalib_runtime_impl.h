/*
 * imucalib_runtime_impl.h - the body of imucalib_runtime.c, written once for both precisions.
 *
 * Not a header to include: imucalib_runtime.c includes it twice (write_c_runtime inlines it
 * there, so the folder it writes stands alone), with IMUCAL_REAL double then float, IMUCAL_NAME(f) adding the _d or _f suffix, IMUCAL_PARAMS the parameter block type,
 * IMUCAL_LIT(x) a literal of that type, IMUCAL_SQRT sqrt or sqrtf, IMUCAL_FABS fabs or fabsf
 * and IMUCAL_EPS DBL_EPSILON or FLT_EPSILON.
 */

/* Eq. (C1): one parameter at (T, Tdot, leg); the powers (T - T0)^j built by repeated products. */
static IMUCAL_REAL IMUCAL_NAME(param)(const IMUCAL_PARAMS *p, int slot, IMUCAL_REAL dt,
                                      IMUCAL_REAL rate, IMUCAL_REAL leg)
{
    const IMUCAL_REAL *c = p->coef[slot];
    IMUCAL_REAL power = IMUCAL_LIT(1.0);
    IMUCAL_REAL sum = c[0];
    int j;
    for (j = 1; j < p->n_terms[slot]; ++j) {
        power *= dt;
        sum += c[j] * power;
    }
    return sum + p->rate[slot] * rate + p->leg[slot] * leg;
}

/* Eq. (C3'): u + K2 u^2 + K3 u^3 = r (K3 != 0) on the branch through 0, by Newton's method from
 * the root of (C3) (1 + 4 K2 r clipped at 0), as imucalib.models.correct does: at most
 * IMUCAL_K3_MAX_ITER steps, stopping where a step is <= 4 epsilon |u|; the root is accepted
 * only where h'(t) = 1 + 2 K2 t + 3 K3 t^2 > 0 for every t between 0 and u. */
static int IMUCAL_NAME(k3_root)(IMUCAL_REAL k2, IMUCAL_REAL k3, IMUCAL_REAL r, IMUCAL_REAL *out)
{
    const IMUCAL_REAL disc = IMUCAL_LIT(1.0) + IMUCAL_LIT(4.0) * k2 * r;
    IMUCAL_REAL u = IMUCAL_LIT(2.0) * r
                    / (IMUCAL_LIT(1.0) + IMUCAL_SQRT(disc > IMUCAL_LIT(0.0) ? disc
                                                                             : IMUCAL_LIT(0.0)));
    IMUCAL_REAL lowest;
    int it, done = 0;
    for (it = 0; it < IMUCAL_K3_MAX_ITER && !done; ++it) {
        const IMUCAL_REAL slope = IMUCAL_LIT(1.0)
                                  + u * (IMUCAL_LIT(2.0) * k2 + IMUCAL_LIT(3.0) * k3 * u);
        const IMUCAL_REAL step = (u + u * u * (k2 + k3 * u) - r) / slope;
        u = u - step;
        done = IMUCAL_FABS(step) <= IMUCAL_LIT(4.0) * IMUCAL_EPS * IMUCAL_FABS(u);
    }
    lowest = IMUCAL_LIT(1.0) + u * (IMUCAL_LIT(2.0) * k2 + IMUCAL_LIT(3.0) * k3 * u);
    if (lowest > IMUCAL_LIT(1.0)) {
        lowest = IMUCAL_LIT(1.0);
    }
    if (k3 > IMUCAL_LIT(0.0)) { /* h' has its minimum at t = -K2 / (3 K3) */
        const IMUCAL_REAL vertex = -k2 / (IMUCAL_LIT(3.0) * k3);
        if (vertex * (vertex - u) < IMUCAL_LIT(0.0) && IMUCAL_LIT(1.0) + k2 * vertex < lowest) {
            lowest = IMUCAL_LIT(1.0) + k2 * vertex;
        }
    }
    if (!done || !(lowest > IMUCAL_LIT(0.0))) {
        return IMUCAL_ERR_K3_RANGE;
    }
    *out = u;
    return IMUCAL_OK;
}

/* Eqs. (C2)-(C4), (C3'): one triad measured -> true; f (may be 0) is the specific force for G. */
static int IMUCAL_NAME(triad)(const IMUCAL_PARAMS *p, int triad, const IMUCAL_REAL y[3],
                              const IMUCAL_REAL *f,
                   IMUCAL_REAL dt, IMUCAL_REAL rate, IMUCAL_REAL leg, IMUCAL_REAL x[3])
{
    const int base = triad * IMUCAL_TRIAD_SLOTS;
    IMUCAL_REAL r[3], a[9], adj[9], det;
    int i, j;
    if (p->model == IMUCAL_MODEL_PER_AXIS) {
        for (i = 0; i < 3; ++i) {
            const IMUCAL_REAL k = IMUCAL_NAME(param)(p, base + IMUCAL_K + i, dt, rate, leg);
            if (k == IMUCAL_LIT(0.0)) {
                return IMUCAL_ERR_SINGULAR;
            }
            r[i] = y[i] / k - IMUCAL_NAME(param)(p, base + IMUCAL_B + i, dt, rate, leg);
        }
        for (i = 0; i < 3; ++i) {
            x[i] = r[i];
        }
        return IMUCAL_OK;
    }
    for (i = 0; i < 3; ++i) {
        r[i] = y[i] - IMUCAL_NAME(param)(p, base + IMUCAL_BIAS + i, dt, rate, leg);
    }
    if (f != 0) {
        IMUCAL_REAL gf[3];
        for (i = 0; i < 3; ++i) {
            gf[i] = IMUCAL_LIT(0.0);
            for (j = 0; j < 3; ++j) {
                gf[i] += IMUCAL_NAME(param)(p, base + IMUCAL_G + 3 * i + j, dt, rate, leg) * f[j];
            }
        }
        for (i = 0; i < 3; ++i) {
            r[i] -= gf[i];
        }
    }
    for (i = 0; i < 3; ++i) {
        const IMUCAL_REAL k2 = IMUCAL_NAME(param)(p, base + IMUCAL_K2 + i, dt, rate, leg);
        const IMUCAL_REAL k3 = IMUCAL_NAME(param)(p, base + IMUCAL_K3 + i, dt, rate, leg);
        if (k3 != IMUCAL_LIT(0.0)) {
            const int rc = IMUCAL_NAME(k3_root)(k2, k3, r[i], &r[i]);
            if (rc != IMUCAL_OK) {
                return rc;
            }
        } else if (k2 != IMUCAL_LIT(0.0)) {
            const IMUCAL_REAL disc = IMUCAL_LIT(1.0) + IMUCAL_LIT(4.0) * k2 * r[i];
            if (!(disc >= IMUCAL_LIT(0.0))) {
                return IMUCAL_ERR_K2_RANGE;
            }
            r[i] = IMUCAL_LIT(2.0) * r[i] / (IMUCAL_LIT(1.0) + IMUCAL_SQRT(disc));
        }
    }
    for (i = 0; i < 9; ++i) {
        a[i] = IMUCAL_NAME(param)(p, base + IMUCAL_M + i, dt, rate, leg)
               + ((i % 4 == 0) ? IMUCAL_LIT(1.0) : IMUCAL_LIT(0.0));
    }
    adj[0] = a[4] * a[8] - a[5] * a[7];
    adj[1] = a[2] * a[7] - a[1] * a[8];
    adj[2] = a[1] * a[5] - a[2] * a[4];
    adj[3] = a[5] * a[6] - a[3] * a[8];
    adj[4] = a[0] * a[8] - a[2] * a[6];
    adj[5] = a[2] * a[3] - a[0] * a[5];
    adj[6] = a[3] * a[7] - a[4] * a[6];
    adj[7] = a[1] * a[6] - a[0] * a[7];
    adj[8] = a[0] * a[4] - a[1] * a[3];
    det = a[0] * adj[0] + a[1] * adj[3] + a[2] * adj[6];
    if (det == IMUCAL_LIT(0.0) || !isfinite(det)) {
        return IMUCAL_ERR_SINGULAR;
    }
    for (i = 0; i < 3; ++i) {
        x[i] = (adj[3 * i] * r[0] + adj[3 * i + 1] * r[1] + adj[3 * i + 2] * r[2]) / det;
    }
    return IMUCAL_OK;
}

int IMUCAL_NAME(imucal_temperature_leg)(IMUCAL_REAL temperature_rate_degc_ps)
{
    if (temperature_rate_degc_ps > (IMUCAL_REAL)IMUCAL_LEG_DEAD_BAND_DEGC_PS) {
        return 1;
    }
    if (temperature_rate_degc_ps < -(IMUCAL_REAL)IMUCAL_LEG_DEAD_BAND_DEGC_PS) {
        return -1;
    }
    return 0;
}

int IMUCAL_NAME(imucal_correct)(const IMUCAL_PARAMS *p, const IMUCAL_REAL gyro_raw[3],
                     const IMUCAL_REAL accel_raw[3], IMUCAL_REAL temperature_degc,
                     IMUCAL_REAL temperature_rate_degc_ps, int leg, IMUCAL_REAL gyro_out[3],
                     IMUCAL_REAL accel_out[3])
{
    IMUCAL_REAL dt = temperature_degc - p->t0_degc;
    IMUCAL_REAL g[3], f[3];
    int i, rc;
    if (!p->has_temperature) { /* temperature, rate and leg are ignored */
        dt = temperature_rate_degc_ps = 0;
        leg = 0;
    } else if (leg < -1 || leg > 1 || !isfinite(dt) || !isfinite(temperature_rate_degc_ps)) {
        return IMUCAL_ERR_INPUT;
    }
    for (i = 0; i < 3; ++i) {
        if (!isfinite(gyro_raw[i]) || !isfinite(accel_raw[i])) {
            return IMUCAL_ERR_INPUT;
        }
        g[i] = gyro_raw[i];
        f[i] = accel_raw[i];
    }
    if (p->has_triad[IMUCAL_ACCEL]) {
        rc = IMUCAL_NAME(triad)(p, IMUCAL_ACCEL, accel_raw, 0, dt, temperature_rate_degc_ps,
                                (IMUCAL_REAL)leg, f);
        if (rc != IMUCAL_OK) {
            return rc;
        }
    }
    if (p->has_triad[IMUCAL_GYRO]) {
        rc = IMUCAL_NAME(triad)(p, IMUCAL_GYRO, gyro_raw, f, dt, temperature_rate_degc_ps,
                                (IMUCAL_REAL)leg, g);
        if (rc != IMUCAL_OK) {
            return rc;
        }
    }
    for (i = 0; i < 3; ++i) {
        gyro_out[i] = g[i];
        accel_out[i] = f[i];
    }
    return IMUCAL_OK;
}
