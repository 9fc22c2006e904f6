/*
 * gk_temperature.c -- the temperature axis of the kernel (docs/model.md "Temperature axis"):
 * gk_set_temperature_axis declares it, gk_set_temperature selects the slices the lookup
 * blends (gk_lookup.h row_interp_t).
 */
#include "gk_internal.h"

int gk_set_temperature_axis(gk_model *m, int n_temp, const double *temperature_C)
{
    int i;
    if (m == NULL || temperature_C == NULL || n_temp < 1) return GK_ERR_MODEL;
    for (i = 0; i < n_temp; ++i) {
        if (!isfinite(temperature_C[i])) return GK_ERR_MODEL;
        if (i > 0 && !(temperature_C[i] > temperature_C[i - 1])) return GK_ERR_MODEL;
    }
    m->n_temp = n_temp;
    m->temperature_C = temperature_C;
    m->temp_ia = 0;
    m->temp_two = 0;
    m->temp_w = 0.0;
    m->temperature_now_C = temperature_C[0];
    gki_node_flags(m);
    return GK_OK;
}

int gk_set_temperature(gk_model *m, double T)
{
    int ia = 0, nt;
    if (m == NULL) return GK_ERR_MODEL;
    if (!isfinite(T)) return GK_ERR_INPUT;
    nt = m->n_temp;
    if (m->temperature_C == NULL) return GK_ERR_INPUT; /* no axis: nothing to select */
    if (T < m->temperature_C[0] || T > m->temperature_C[nt - 1]) return GK_ERR_INPUT;
    while (ia < nt - 1 && m->temperature_C[ia + 1] <= T) ia++;
    m->temp_ia = ia;
    if (m->temperature_C[ia] == T) {
        m->temp_two = 0;
        m->temp_w = 0.0;
    } else {
        m->temp_two = 1;
        m->temp_w = (T - m->temperature_C[ia]) / (m->temperature_C[ia + 1] - m->temperature_C[ia]);
    }
    m->temperature_now_C = T;
    return GK_OK;
}
