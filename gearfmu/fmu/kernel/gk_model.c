/*
 * gk_model.c -- the model of the kernel (gearkernel.h): its size for a caller without the
 * header, gk_init (the tables borrowed, the scalars checked, the derived constants) and the
 * setters of the damping, the integrator and the contact-zone cuts.  The temperature axis is
 * gk_temperature.c; the cuts themselves gk_zones.c.
 */
#include "gk_internal.h"

int gk_abi_version(void) { return GK_ABI_VERSION; }
int gk_sizeof_model(void) { return (int)sizeof(gk_model); }
int gk_sizeof_state(void) { return (int)sizeof(gk_state); }
int gk_n_outputs(int P) { return GK_OUT_PAIR_FORCE + 2 * P; }
int gk_sizeof_me(void) { return (int)sizeof(gk_me); }
int gk_me_n_outputs(int P) { return GK_ME_OUT_INDICATORS + 4 * P + 2; }

int gk_init(gk_model *m, int P, int n_phi, int n_torque,
            const double *torque_Nm, const double *k_N_per_m,
            const double *e_m, const double *backlash_half_m,
            double phi_period_rad, double Rb1_m, double Rb2_m,
            double I1_kgm2, double I2_kgm2, double k_mean_N_per_m)
{
    int i;
    if (m == NULL || torque_Nm == NULL || k_N_per_m == NULL || e_m == NULL || backlash_half_m == NULL)
        return GK_ERR_MODEL;
    if (P < 1 || n_phi < 2 || n_torque < 1)
        return GK_ERR_MODEL;
    if (!gki_finite_pos(phi_period_rad) || !gki_finite_pos(Rb1_m) || !gki_finite_pos(Rb2_m) ||
        !gki_finite_pos(I1_kgm2) || !gki_finite_pos(I2_kgm2) || !gki_finite_pos(k_mean_N_per_m))
        return GK_ERR_MODEL;
    for (i = 0; i < n_torque; ++i) {
        if (!isfinite(torque_Nm[i])) return GK_ERR_MODEL;
        if (i > 0 && !(torque_Nm[i] > torque_Nm[i - 1])) return GK_ERR_MODEL;
    }
    m->P = P;
    m->n_phi = n_phi;
    m->n_torque = n_torque;
    m->torque_Nm = torque_Nm;
    m->k_N_per_m = k_N_per_m;
    m->e_m = e_m;
    m->backlash_half_m = backlash_half_m;
    m->phi_period_rad = phi_period_rad;
    m->dphi_rad = phi_period_rad / n_phi;
    m->inv_dphi = (double)n_phi / phi_period_rad;
    m->Rb1_m = Rb1_m;
    m->Rb2_m = Rb2_m;
    m->I1_kgm2 = I1_kgm2;
    m->I2_kgm2 = I2_kgm2;
    m->inv_I1 = 1.0 / I1_kgm2;
    m->inv_I2 = 1.0 / I2_kgm2;
    m->seg_gw = Rb1_m / I1_kgm2;
    m->seg_gv = Rb1_m * (Rb1_m / I1_kgm2) + Rb2_m * (Rb2_m / I2_kgm2);
    m->k_mean_N_per_m = k_mean_N_per_m;
    /* m_e = I1 I2 / (I1 Rb2^2 + I2 Rb1^2), Xu et al. 2022 below eq 2 */
    m->m_e_kg = I1_kgm2 * I2_kgm2 / (I1_kgm2 * Rb2_m * Rb2_m + I2_kgm2 * Rb1_m * Rb1_m);
    m->damping_ratio = 0.0;
    m->c_Ns_per_m = 0.0;
    m->damping_model = GK_DAMPING_ELASTOBACKLASH;
    m->integrator = GK_INTEGRATOR_RK4;
    m->seg_stops = GK_STOPS_SEG;
    m->n_temp = 1;
    m->temperature_C = NULL;
    m->temp_ia = 0;
    m->temp_two = 0;
    m->temp_w = 0.0;
    m->temperature_now_C = 0.0;
    m->zone_cuts = NULL;
    m->zone_n_mesh = 0.0;
    m->zone_ppm = m->zone_in = m->zone_out = 0.0;
    gki_node_flags(m);
    return GK_OK;
}

int gk_set_zone_cuts(gk_model *m, const double *cuts)
{
    if (m == NULL) return GK_ERR_MODEL;
    m->zone_cuts = cuts;
    gki_node_flags(m);   /* the rk4_seg stops include the cells with an edge */
    return GK_OK;
}

int gk_set_integrator(gk_model *m, int integrator)
{
    if (m == NULL) return GK_ERR_MODEL;
    if (integrator == GK_INTEGRATOR_RK4) {
        m->integrator = integrator;
        return GK_OK;
    }
    if ((integrator == GK_INTEGRATOR_RK4_KINK || integrator == GK_INTEGRATOR_RK4_NODE
         || integrator == GK_INTEGRATOR_RK4_SEG) && m->P <= GK_KINK_MAX_SLOTS) {
        m->integrator = integrator;
        return GK_OK;
    }
    return GK_ERR_PARAM;
}

int gk_set_damping(gk_model *m, double damping_ratio, int damping_model)
{
    if (m == NULL) return GK_ERR_MODEL;
    if (!isfinite(damping_ratio) || damping_ratio < 0.0) return GK_ERR_PARAM;
    if (damping_model != GK_DAMPING_ELASTOBACKLASH && damping_model != GK_DAMPING_CONTACT_ZONE)
        return GK_ERR_PARAM;
    m->damping_ratio = damping_ratio;
    m->c_Ns_per_m = 2.0 * damping_ratio * sqrt(m->k_mean_N_per_m * m->m_e_kg);
    m->damping_model = damping_model;
    return GK_OK;
}
