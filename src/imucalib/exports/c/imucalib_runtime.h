/*
 * imucalib_runtime.h - apply an imucalib calibration to raw IMU samples (C99, no allocation).
 *
 * Fixed library, copied next to a generated <name>_params.h by imucalib's "c-runtime" export
 * (docs/c-runtime.md). One call per sample; the parameter block is read-only and the functions
 * keep no state, so they are reentrant.
 *
 * Model (docs/c-runtime.md, Eqs. (C1)-(C4); the same as imucalib.models.correct.correct_imu):
 *   p(T, Tdot, leg) = sum_j c_j (T - T0)^j + d*Tdot + h*leg                       (C1)
 *   triad:     y = b + h((I + M) x) (+ G f, gyro),  h_i(u) = u + K2_i u^2 + K3_i u^3   (C2)
 *              u_i = 2 r_i / (1 + sqrt(1 + 4 K2_i r_i)),  r = y - b (- G f)        (C3)
 *              K3_i != 0: Newton steps on h_i(u) = r_i from that root            (C3')
 *              x = (I + M)^-1 u
 *   per-axis:  y_i = K_i (x_i + b_i)  ->  x_i = y_i / K_i - b_i                    (C4)
 * The accelerometer is corrected first; its corrected specific force f feeds the gyro's G.
 * Units: those of the result's input_units (SI: rad/s, m/s^2), temperature in degC, its rate
 * in degC/s, leg in {-1, 0, +1}.
 */
#ifndef IMUCALIB_RUNTIME_H
#define IMUCALIB_RUNTIME_H

#ifdef __cplusplus
extern "C" {
#endif

/* Parameter slots of one triad (t = IMUCAL_GYRO or IMUCAL_ACCEL): slot = t * IMUCAL_TRIAD_SLOTS
 * + offset; the 3 x 3 matrices row-major (row: sensor axis, column: input axis).
 * Layout version 2 appended IMUCAL_K3 at the end of a triad's slots (version 1: 30 slots a
 * triad, no K3); a generated <name>_params.h refuses to compile against another layout. */
#define IMUCAL_LAYOUT_VERSION 2
#define IMUCAL_GYRO 0
#define IMUCAL_ACCEL 1
#define IMUCAL_BIAS 0   /* b_x b_y b_z of a triad model */
#define IMUCAL_M 3      /* M_xx M_xy ... M_zz */
#define IMUCAL_G 12     /* G_xx ... G_zz (gyro g-sensitivity) */
#define IMUCAL_K2 21    /* K2_x K2_y K2_z (quadratic scale factor) */
#define IMUCAL_K 24     /* K_x K_y K_z of a per-axis model */
#define IMUCAL_B 27     /* b_x b_y b_z of a per-axis model (input units) */
#define IMUCAL_K3 30    /* K3_x K3_y K3_z (cubic scale factor; layout version 2) */
#define IMUCAL_TRIAD_SLOTS 33
#define IMUCAL_N_SLOTS 66
/* Polynomial terms c_0 ... c_7 of Eq. (C1) per slot (order 7 at most). */
#define IMUCAL_MAX_TERMS 8

/* imucal_params_*.model */
#define IMUCAL_MODEL_TRIAD 0
#define IMUCAL_MODEL_PER_AXIS 1

/* Return codes */
#define IMUCAL_OK 0
#define IMUCAL_ERR_INPUT 1       /* a non-finite input, or leg not in {-1, 0, +1} */
#define IMUCAL_ERR_SINGULAR 2    /* I + M singular (or K_i = 0) at this temperature */
#define IMUCAL_ERR_K2_RANGE 3    /* 1 + 4 K2_i r_i < 0: outside the invertible range */
#define IMUCAL_ERR_K3_RANGE 4    /* K3_i != 0: no root on the branch through 0 (h not monotonic
                                  * between 0 and it), or no convergence (C3') */

/* Newton steps of Eq. (C3') at most; it stops where a step is <= 4 epsilon |u|. */
#define IMUCAL_K3_MAX_ITER 20

/* Dead band of imucal_temperature_leg_*: |Tdot| at or below it is leg 0. [degC/s] */
#define IMUCAL_LEG_DEAD_BAND_DEGC_PS 0.002

typedef struct {
    int model;                 /* IMUCAL_MODEL_TRIAD or IMUCAL_MODEL_PER_AXIS */
    int has_triad[2];          /* [IMUCAL_GYRO], [IMUCAL_ACCEL]: 1 if calibrated */
    int has_temperature;       /* 1 if any parameter has a temperature model */
    double t0_degc;            /* T0 of Eq. (C1) [degC] */
    int n_terms[IMUCAL_N_SLOTS];                   /* polynomial terms used, >= 1 */
    double coef[IMUCAL_N_SLOTS][IMUCAL_MAX_TERMS]; /* c_0 (the value at T0) ... c_m */
    double rate[IMUCAL_N_SLOTS];                   /* d [unit per degC/s] (0: none) */
    double leg[IMUCAL_N_SLOTS];                    /* h [unit] (0: none) */
} imucal_params_d;

typedef struct {
    int model;
    int has_triad[2];
    int has_temperature;
    float t0_degc;
    int n_terms[IMUCAL_N_SLOTS];
    float coef[IMUCAL_N_SLOTS][IMUCAL_MAX_TERMS];
    float rate[IMUCAL_N_SLOTS];
    float leg[IMUCAL_N_SLOTS];
} imucal_params_f;

/* Correct one sample. gyro_raw [rad/s], accel_raw [m/s^2] (sensor axes), temperature [degC],
 * its rate [degC/s] and the leg (+1 heating, -1 cooling, 0 mean of both) are ignored by a
 * calibration without temperature models. A triad the calibration does not cover is copied.
 * gyro_out / accel_out may alias the inputs. Returns IMUCAL_OK or an IMUCAL_ERR_* code (the
 * outputs are then left unspecified). */
int imucal_correct_d(const imucal_params_d *p, const double gyro_raw[3],
                     const double accel_raw[3], double temperature_degc,
                     double temperature_rate_degc_ps, int leg, double gyro_out[3],
                     double accel_out[3]);
int imucal_correct_f(const imucal_params_f *p, const float gyro_raw[3], const float accel_raw[3],
                     float temperature_degc, float temperature_rate_degc_ps, int leg,
                     float gyro_out[3], float accel_out[3]);

/* The leg of a temperature rate: sign(Tdot) outside IMUCAL_LEG_DEAD_BAND_DEGC_PS, else 0. */
int imucal_temperature_leg_d(double temperature_rate_degc_ps);
int imucal_temperature_leg_f(float temperature_rate_degc_ps);

#ifdef __cplusplus
}
#endif

#endif /* IMUCALIB_RUNTIME_H */
