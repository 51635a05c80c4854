/*
 * imucalib_runtime.c - apply an imucalib calibration to raw IMU samples (C99 + math.h).
 *
 * See imucalib_runtime.h and docs/c-runtime.md. No allocation, no state: every function reads
 * its parameter block and its arguments only. The float functions repeat the double ones with
 * float arithmetic (sqrtf), so that a target without a double-precision FPU needs no double.
 */
#include <math.h>

#include "imucalib_runtime.h"

/* ---- double ------------------------------------------------------------------------------- */

/* Eq. (C1): one parameter at (T, Tdot, leg); the powers (T - T0)^j built by repeated products. */
static double param_d(const imucal_params_d *p, int slot, double dt, double rate, double leg)
{
    const double *c = p->coef[slot];
    double power = 1.0;
    double sum = c[0];
    int j;
    for (j = 1; j < p->n_terms[slot]; ++j) {
        power *= dt;
        sum += c[j] * power;
    }
    return sum + p->rate[slot] * rate + p->leg[slot] * leg;
}

/* Eqs. (C2)-(C4): one triad measured -> true; f (may be 0) is the specific force for G. */
static int triad_d(const imucal_params_d *p, int triad, const double y[3], const double *f,
                   double dt, double rate, double leg, double x[3])
{
    const int base = triad * IMUCAL_TRIAD_SLOTS;
    double r[3], a[9], adj[9], det;
    int i, j;
    if (p->model == IMUCAL_MODEL_PER_AXIS) {
        for (i = 0; i < 3; ++i) {
            const double k = param_d(p, base + IMUCAL_K + i, dt, rate, leg);
            if (k == 0.0) {
                return IMUCAL_ERR_SINGULAR;
            }
            r[i] = y[i] / k - param_d(p, base + IMUCAL_B + i, dt, rate, leg);
        }
        for (i = 0; i < 3; ++i) {
            x[i] = r[i];
        }
        return IMUCAL_OK;
    }
    for (i = 0; i < 3; ++i) {
        r[i] = y[i] - param_d(p, base + IMUCAL_BIAS + i, dt, rate, leg);
    }
    if (f != 0) {
        double gf[3];
        for (i = 0; i < 3; ++i) {
            gf[i] = 0.0;
            for (j = 0; j < 3; ++j) {
                gf[i] += param_d(p, base + IMUCAL_G + 3 * i + j, dt, rate, leg) * f[j];
            }
        }
        for (i = 0; i < 3; ++i) {
            r[i] -= gf[i];
        }
    }
    for (i = 0; i < 3; ++i) {
        const double k2 = param_d(p, base + IMUCAL_K2 + i, dt, rate, leg);
        if (k2 != 0.0) {
            const double disc = 1.0 + 4.0 * k2 * r[i];
            if (!(disc >= 0.0)) {
                return IMUCAL_ERR_K2_RANGE;
            }
            r[i] = 2.0 * r[i] / (1.0 + sqrt(disc));
        }
    }
    for (i = 0; i < 9; ++i) {
        a[i] = param_d(p, base + IMUCAL_M + i, dt, rate, leg) + ((i % 4 == 0) ? 1.0 : 0.0);
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
    if (det == 0.0 || !isfinite(det)) {
        return IMUCAL_ERR_SINGULAR;
    }
    for (i = 0; i < 3; ++i) {
        x[i] = (adj[3 * i] * r[0] + adj[3 * i + 1] * r[1] + adj[3 * i + 2] * r[2]) / det;
    }
    return IMUCAL_OK;
}

int imucal_temperature_leg_d(double temperature_rate_degc_ps)
{
    if (temperature_rate_degc_ps > IMUCAL_LEG_DEAD_BAND_DEGC_PS) {
        return 1;
    }
    if (temperature_rate_degc_ps < -IMUCAL_LEG_DEAD_BAND_DEGC_PS) {
        return -1;
    }
    return 0;
}

int imucal_correct_d(const imucal_params_d *p, const double gyro_raw[3],
                     const double accel_raw[3], double temperature_degc,
                     double temperature_rate_degc_ps, int leg, double gyro_out[3],
                     double accel_out[3])
{
    double dt = temperature_degc - p->t0_degc;
    double g[3], f[3];
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
        rc = triad_d(p, IMUCAL_ACCEL, accel_raw, 0, dt, temperature_rate_degc_ps, (double)leg,
                     f);
        if (rc != IMUCAL_OK) {
            return rc;
        }
    }
    if (p->has_triad[IMUCAL_GYRO]) {
        rc = triad_d(p, IMUCAL_GYRO, gyro_raw, f, dt, temperature_rate_degc_ps, (double)leg, g);
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

/* ---- float --------------------------------------------------------------------------------- */

/* Eq. (C1): one parameter at (T, Tdot, leg); the powers (T - T0)^j built by repeated products. */
static float param_f(const imucal_params_f *p, int slot, float dt, float rate, float leg)
{
    const float *c = p->coef[slot];
    float power = 1.0f;
    float sum = c[0];
    int j;
    for (j = 1; j < p->n_terms[slot]; ++j) {
        power *= dt;
        sum += c[j] * power;
    }
    return sum + p->rate[slot] * rate + p->leg[slot] * leg;
}

/* Eqs. (C2)-(C4): one triad measured -> true; f (may be 0) is the specific force for G. */
static int triad_f(const imucal_params_f *p, int triad, const float y[3], const float *f,
                   float dt, float rate, float leg, float x[3])
{
    const int base = triad * IMUCAL_TRIAD_SLOTS;
    float r[3], a[9], adj[9], det;
    int i, j;
    if (p->model == IMUCAL_MODEL_PER_AXIS) {
        for (i = 0; i < 3; ++i) {
            const float k = param_f(p, base + IMUCAL_K + i, dt, rate, leg);
            if (k == 0.0f) {
                return IMUCAL_ERR_SINGULAR;
            }
            r[i] = y[i] / k - param_f(p, base + IMUCAL_B + i, dt, rate, leg);
        }
        for (i = 0; i < 3; ++i) {
            x[i] = r[i];
        }
        return IMUCAL_OK;
    }
    for (i = 0; i < 3; ++i) {
        r[i] = y[i] - param_f(p, base + IMUCAL_BIAS + i, dt, rate, leg);
    }
    if (f != 0) {
        float gf[3];
        for (i = 0; i < 3; ++i) {
            gf[i] = 0.0f;
            for (j = 0; j < 3; ++j) {
                gf[i] += param_f(p, base + IMUCAL_G + 3 * i + j, dt, rate, leg) * f[j];
            }
        }
        for (i = 0; i < 3; ++i) {
            r[i] -= gf[i];
        }
    }
    for (i = 0; i < 3; ++i) {
        const float k2 = param_f(p, base + IMUCAL_K2 + i, dt, rate, leg);
        if (k2 != 0.0f) {
            const float disc = 1.0f + 4.0f * k2 * r[i];
            if (!(disc >= 0.0f)) {
                return IMUCAL_ERR_K2_RANGE;
            }
            r[i] = 2.0f * r[i] / (1.0f + sqrtf(disc));
        }
    }
    for (i = 0; i < 9; ++i) {
        a[i] = param_f(p, base + IMUCAL_M + i, dt, rate, leg) + ((i % 4 == 0) ? 1.0f : 0.0f);
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
    if (det == 0.0f || !isfinite(det)) {
        return IMUCAL_ERR_SINGULAR;
    }
    for (i = 0; i < 3; ++i) {
        x[i] = (adj[3 * i] * r[0] + adj[3 * i + 1] * r[1] + adj[3 * i + 2] * r[2]) / det;
    }
    return IMUCAL_OK;
}

int imucal_temperature_leg_f(float temperature_rate_degc_ps)
{
    if (temperature_rate_degc_ps > (float)IMUCAL_LEG_DEAD_BAND_DEGC_PS) {
        return 1;
    }
    if (temperature_rate_degc_ps < -(float)IMUCAL_LEG_DEAD_BAND_DEGC_PS) {
        return -1;
    }
    return 0;
}

int imucal_correct_f(const imucal_params_f *p, const float gyro_raw[3],
                     const float accel_raw[3], float temperature_degc,
                     float temperature_rate_degc_ps, int leg, float gyro_out[3],
                     float accel_out[3])
{
    float dt = temperature_degc - p->t0_degc;
    float g[3], f[3];
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
        rc = triad_f(p, IMUCAL_ACCEL, accel_raw, 0, dt, temperature_rate_degc_ps, (float)leg,
                     f);
        if (rc != IMUCAL_OK) {
            return rc;
        }
    }
    if (p->has_triad[IMUCAL_GYRO]) {
        rc = triad_f(p, IMUCAL_GYRO, gyro_raw, f, dt, temperature_rate_degc_ps, (float)leg, g);
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
