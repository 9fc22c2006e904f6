/*
 * gk_envelope.c -- the verified envelope of the FMU (docs/fmu.md "Verified envelope";
 * gearkernel.h): the input ranges over which the FMU's accuracy was verified, and the one
 * warning per quantity both FMU runtimes give when an input leaves its range.
 */
#include <math.h>
#include <stddef.h>
#include <stdio.h>

#include "gearkernel.h"

int gk_sizeof_envelope(void) { return (int)sizeof(gk_envelope); }

int gk_envelope_init(gk_envelope *e, int kind)
{
    int q;
    if (e == NULL || kind < GK_ENV_VERIFIED || kind > GK_ENV_NOT_VERIFIED) return GK_ERR_PARAM;
    for (q = 0; q < GK_ENV_N; ++q) {
        e->lo[q] = 0.0;
        e->hi[q] = 0.0;
        e->active[q] = 0;
        e->warned[q] = 0;
    }
    e->kind = kind;
    return GK_OK;
}

int gk_envelope_set(gk_envelope *e, int q, double lo_SI, double hi_SI)
{
    if (e == NULL || q < 0 || q >= GK_ENV_N) return GK_ERR_PARAM;
    if (!(isfinite(lo_SI) && isfinite(hi_SI) && lo_SI <= hi_SI)) {
        e->active[q] = 0;
        return GK_ERR_PARAM;
    }
    e->lo[q] = lo_SI;
    e->hi[q] = hi_SI;
    e->active[q] = 1;
    return GK_OK;
}

void gk_envelope_rearm(gk_envelope *e)
{
    int q;
    if (e == NULL) return;
    for (q = 0; q < GK_ENV_N; ++q) e->warned[q] = 0;
}

int gk_envelope_check(gk_envelope *e, int q, const char *name, double value, double t_s, char *msg, int cap)
{
    static const char *const what[3] = {
        "the envelope over which this FMU's accuracy was verified (fidelity plan)",
        "the envelope over which this FMU's accuracy was estimated (as-written estimate, not verified)",
        "the range this FMU was built for (its tables' range; accuracy not verified)"};
    static const char *const quantity[GK_ENV_N] = {"pinion torque", "pinion speed", "temperature"};
    static const char *const unit[GK_ENV_N] = {"N.m", "rad/s", "degC"};
    double lo, hi;
    if (e == NULL || q < 0 || q >= GK_ENV_N || !e->active[q] || e->warned[q] || isnan(value)) return 0;
    lo = e->lo[q];
    hi = e->hi[q];
    if (q == GK_ENV_PINION_SPEED) {
        lo -= GK_ENV_SPEED_MARGIN * fabs(lo);
        hi += GK_ENV_SPEED_MARGIN * fabs(hi);
    }
    if (value >= lo && value <= hi) return 0;
    e->warned[q] = 1;
    if (msg == NULL || cap <= 0) return 1;
    if (q == GK_ENV_PINION_SPEED) {
        const double rpm = 30.0 / 3.14159265358979323846;
        snprintf(msg, (size_t)cap,
                 "%s = %.9g rad/s (%.9g rpm) at t = %.9g s is outside %s: pinion speed [%.9g, %.9g] rad/s "
                 "([%.9g, %.9g] rpm; compared with a %g percent margin for the torsional vibration); the FMU keeps "
                 "running, its accuracy there is not known (one warning per input; resources/envelope.json)",
                 name ? name : "pinion_speed", value, value * rpm, t_s, what[e->kind], e->lo[q], e->hi[q],
                 e->lo[q] * rpm, e->hi[q] * rpm, 100.0 * GK_ENV_SPEED_MARGIN);
    } else {
        snprintf(msg, (size_t)cap,
                 "%s = %.9g %s at t = %.9g s is outside %s: %s [%.9g, %.9g] %s; the FMU keeps running, its "
                 "accuracy there is not known (one warning per input; resources/envelope.json)",
                 name ? name : quantity[q], value, unit[q], t_s, what[e->kind], quantity[q], e->lo[q], e->hi[q],
                 unit[q]);
    }
    return 1;
}
