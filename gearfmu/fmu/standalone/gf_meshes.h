/*
 * gf_meshes.h -- what the multi-mesh models of the standalone runtime share (gf_meshes.c): the gearbox
 * model (gearbox_model.c, docs/gearbox.md "The gearbox FMU") and the planetary model (planetary_model.c,
 * docs/planetary.md "The planetary FMU").  Both are a kernel of several meshes -- every mesh a pair
 * model of gearkernel.h on its own tables -- driven by the same parameters and inputs (the motor and
 * load torques, the start speed and angle, the largest step, the integrator, every mesh's damping
 * ratio and law), so the behaviour around the kernel is one:
 *
 *   the configuration lines both configurations have (format, guid, torque inputs, the value
 *   references the model drives, the interfaces, Model Exchange, the variable table) and a mesh's
 *   tables keys (<prefix>.<i>.tables, .slots, .offset.*, the scalars, .vr.damping_*);
 *   a mesh's tables file read, its size and SHA-256 checked, its pair model and contact-zone cuts set up
 *   (meshes naming one file share its bytes);
 *   the parameter checks, the initial state, a communication step, the torque-axis warnings, Model
 *   Exchange (gf_model.h gf_me_model) and the FMU state snapshot.
 *
 * A model keeps a gfm_core as the FIRST member of its gm_data, points it at its kernel through the
 * function table gfm_kernel (its kernel's functions over the model's own data) and at its state (by
 * offsets into its data), and calls the gfm_* functions from its gm_* functions.  Nothing here calls back into a model file except
 * through that table.
 */
#ifndef GF_MESHES_H
#define GF_MESHES_H

#include <stddef.h>
#include <stdint.h>

#include "gearkernel.h"
#include "gf_model.h"
#include "gf_resources.h"

#define GFM_MAX_MESHES 32
#define GFM_NUM 40
#define GFM_MAX_STATE 192
/* the integrator parameter's codes 0 .. GFM_INTEGRATORS - 1 (rk4, rk4_kink, rk4_node, rk4_seg) */
#define GFM_INTEGRATORS 4

/* the kernel of a multi-mesh model, as the shared behaviour calls it (kd: the model's data) */
typedef struct gfm_kernel {
    const char *mesh_word;   /* what a mesh is called in messages: "stage", "mesh" */
    const char *doc;         /* the documentation page messages point to */
    int (*k_integrator)(void *kd, int code);
    double (*k_tref)(const void *kd, double Tm, double Tl);
    double (*k_mesh_torque)(const void *kd, int m, double t_ref);
    int (*k_initialize)(void *kd, double psi0, double w0, double t_ref, int *bad_mesh);
    int (*k_outputs)(void *kd, double Tm, double Tl, double *out);
    int (*k_step)(void *kd, double Tm, double Tl, double H, double hmax, double *out);
    int (*k_me_n_ind)(const void *kd, int node_events);
    int (*k_me_init)(void *kd, double Tm, double Tl, int node_events);
    int (*k_me_update)(void *kd, double Tm, double Tl, int *changed);
    int (*k_me_deriv)(void *kd, double Tm, double Tl, double *dy);
    int (*k_me_ind)(void *kd, double Tm, double Tl, double *z);
    int (*k_me_out)(void *kd, double Tm, double Tl, double *out);
} gfm_kernel;

/* a mesh's keys in a configuration (<prefix>.<i>.<key>) */
typedef struct {
    char name[GF_MAX_NAME], file[GF_MAX_NAME * 2], sha[65];
    long P, n_phi, n_torque, bytes, off_torque, off_k, off_e, off_b;
    double phi_period, Rb1, Rb2, I1, I2, k_mean, mesh_period, eng_in, eng_out;
    long vr_zeta, vr_dm;
    unsigned have;   /* GFM_K_* bits of the keys read; a model adds its own bits from GFM_K_NEXT up */
} gfm_mesh_cfg;

enum {
    GFM_K_NAME = 1 << 0, GFM_K_FILE = 1 << 1, GFM_K_SHA = 1 << 2, GFM_K_P = 1 << 3, GFM_K_NPHI = 1 << 4,
    GFM_K_NT = 1 << 5, GFM_K_BYTES = 1 << 6, GFM_K_OT = 1 << 7, GFM_K_OK = 1 << 8, GFM_K_OE = 1 << 9,
    GFM_K_OB = 1 << 10, GFM_K_PHI = 1 << 11, GFM_K_RB1 = 1 << 12, GFM_K_RB2 = 1 << 13, GFM_K_I1 = 1 << 14,
    GFM_K_I2 = 1 << 15, GFM_K_KM = 1 << 16, GFM_K_VRZ = 1 << 17, GFM_K_VRDM = 1 << 18,
    GFM_K_ALL = (1 << 19) - 1, GFM_K_NEXT = 1 << 19
};

/* the lines both configurations have */
typedef struct {
    char guid[GF_MAX_NAME];
    long motor_input, load_input;
    long vr_motor_torque, vr_load_torque, vr_speed0, vr_angle0, vr_hmax, vr_integrator;
    long extra_outputs;   /* outputs past the kernel's, filled by a model around this one (stage_model.c) */
    long state_outputs;   /* 1: the kernel state follows the outputs (without Model Exchange too) */
    int offers, me_node_events, have_nominals;
    long me_indicators, me_n_nominals;
    double me_nominal[GFM_MAX_STATE];
    int have_format, have_guid, have_nvars, nvar_seen;
} gfm_common_cfg;

/* what the shared behaviour keeps (the first member of a multi-mesh model's gm_data) */
typedef struct gfm_core {
    const gfm_kernel *k;                   /* its functions take the model's data (gm_data, which starts here) */
    /* where in the model's data (byte offsets from its start: the data may move, stage_model.c reallocates
     * it) the kernel state's vector (n_state values), the kernel state and its Model Exchange modes are */
    size_t y_offset, kstate_offset, kme_offset;
    size_t n_state;
    size_t kstate_bytes, kme_bytes;
    uint32_t snap_magic, snap_version;
    int n_mesh;
    unsigned char *blob[GFM_MAX_MESHES];   /* each mesh's tables.bin (owned unless blob_shared) */
    int blob_shared[GFM_MAX_MESHES];      /* 1: another mesh's (same file) */
    char file[GFM_MAX_MESHES][GF_MAX_NAME * 2], sha[GFM_MAX_MESHES][65];
    long bytes[GFM_MAX_MESHES];
    double *cuts[GFM_MAX_MESHES];          /* its contact-zone cuts (gk_zone_cuts), NULL: none */
    gk_model *pair[GFM_MAX_MESHES];        /* its pair model */
    char name[GFM_MAX_MESHES][GF_MAX_NAME];
    uint64_t tables_tag;                   /* first 8 bytes of the SHA-256 of the meshes' checksums */
    int vr_motor_torque, vr_load_torque, vr_speed0, vr_angle0, vr_hmax, vr_integrator;
    int vr_zeta[GFM_MAX_MESHES], vr_dm[GFM_MAX_MESHES];
    double zeta_applied[GFM_MAX_MESHES];
    int zeta_valid;
    uint32_t warned;                       /* bit m: mesh m's torque-axis warning was given */
    int initialized;
    int me_offered, me_node_events, me_base;
    int state_base;                        /* the kernel state in the outputs from here (-1: not there) */
    double me_nominal[GFM_MAX_STATE];
} gfm_core;

/* x as Python's repr writes a float (the rule of ../kernel/gkfmu.c num) */
GF_API const char *gfm_num(double x, char buf[GFM_NUM]);
/* n '|'-separated integers of val; 1 on success */
GF_API int gfm_parse_ints(char *val, long *out, int n);
/* one line key=val of the configuration's common keys: 1 handled, 0 not a common key, -1 bad (err) */
GF_API int gfm_common_key(gf_inst *c, gfm_common_cfg *cc, const char *format, long version, const char *key,
                          char *val, char *err, size_t errcap);
/* a mesh's key k (after "<prefix>.<i>."): 1 handled, 0 not a table key, -1 bad value */
GF_API int gfm_mesh_key(gfm_mesh_cfg *s, const char *k, char *val);
/* the common keys' completeness (NULL, or a message in err) */
GF_API const char *gfm_common_check(const gf_inst *c, const gfm_common_cfg *cc, char *err, size_t errcap);
/* mesh m: its tables file read (or shared with an earlier mesh of the same file), size and SHA-256
 * checked, its pair model and cuts set up, its damping value references bound; NULL or a message */
GF_API const char *gfm_load_mesh(gf_inst *c, gfm_core *core, const char *res_dir, const gfm_mesh_cfg *s, int m,
                                 gf_sha256 *tag, char *err, size_t errcap);
/* the value references of the common keys bound (checked), the outputs (n_kernel_out + extra and,
 * with Model Exchange, its block) allocated, the tables tag set; NULL or a message */
GF_API const char *gfm_bind(gf_inst *c, gfm_core *core, const gfm_common_cfg *cc, int n_kernel_out,
                            gf_sha256 *tag, char *err, size_t errcap);
GF_API void gfm_free(gfm_core *core);
GF_API void gfm_reset(gf_inst *c, gfm_core *core);

GF_API double gfm_val(const gf_inst *c, int vr);
GF_API int gfm_code_of(double x, int n);
/* a value reference of the configuration: -1 (none, 1 if optional) or a parameter or input of the table */
GF_API int gfm_vr_ok(const gf_inst *c, long vr, int optional);
GF_API int gfm_bad_value(gf_inst *c, int vr, int status, const char *tail);

/* the behaviour (the gm_* of gf_model.h for a multi-mesh model; core = c->data's first member) */
GF_API int gfm_init_state(gf_inst *c);
GF_API int gfm_exit_init(gf_inst *c);
GF_API int gfm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr);
GF_API int gfm_do_step(gf_inst *c, double t, double H);
GF_API size_t gfm_snap_size(const gf_inst *c);
GF_API void gfm_snap_write(const gf_inst *c, unsigned char *p);
GF_API int gfm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn);
GF_API int gfm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size);

#endif /* GF_MESHES_H */
