/*
 * imucalib_runtime.c - apply an imucalib calibration to raw IMU samples (C99 + math.h).
 *
 * See imucalib_runtime.h and docs/c-runtime.md. No allocation, no state: every function reads
 * its parameter block and its arguments only. The float functions are the double ones compiled
 * with float arithmetic (sqrtf, fabsf, FLT_EPSILON), so that a target without a double-precision FPU needs no double:
 * imucalib_runtime_impl.h holds the body once, included here for each precision.
 */
#include <float.h>
#include <math.h>

#include "imucalib_runtime.h"

/* ---- double ------------------------------------------------------------------------------- */
#define IMUCAL_REAL double
#define IMUCAL_NAME(f) f##_d
#define IMUCAL_PARAMS imucal_params_d
#define IMUCAL_LIT(x) x
#define IMUCAL_SQRT sqrt
#define IMUCAL_FABS fabs
#define IMUCAL_EPS DBL_EPSILON
#include "imucalib_runtime_impl.h"
#undef IMUCAL_REAL
#undef IMUCAL_NAME
#undef IMUCAL_PARAMS
#undef IMUCAL_LIT
#undef IMUCAL_SQRT
#undef IMUCAL_FABS
#undef IMUCAL_EPS

/* ---- float -------------------------------------------------------------------------------- */
#define IMUCAL_REAL float
#define IMUCAL_NAME(f) f##_f
#define IMUCAL_PARAMS imucal_params_f
#define IMUCAL_LIT(x) x##f
#define IMUCAL_SQRT sqrtf
#define IMUCAL_FABS fabsf
#define IMUCAL_EPS FLT_EPSILON
#include "imucalib_runtime_impl.h"
#undef IMUCAL_REAL
#undef IMUCAL_NAME
#undef IMUCAL_PARAMS
#undef IMUCAL_LIT
#undef IMUCAL_SQRT
#undef IMUCAL_FABS
#undef IMUCAL_EPS
