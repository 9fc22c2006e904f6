/*
 * gk_internal.h -- what the files of the kernel share and nothing outside it sees
 * (the public contract is gearkernel.h):
 *
 *   gearkernel.c     the hot path: RK4, the right-hand sides with the mode held (rk4_kink,
 *                    rk4_node, rk4_seg), the event-location loop, gk_initialize, gk_outputs,
 *                    gk_do_step;
 *   gk_pair.h        the per-mesh pieces the pair and the gearbox kernel (gb_kernel.c) share:
 *                    the mesh force, the force law and guards with the mode held, the mode
 *                    decisions, the root finder (inlined);
 *   gk_lookup.h      the table lookup (inlined into the hot path);
 *   gk_model.c       the model: gk_init and its setters (damping, integrator, zone cuts);
 *   gk_stops.c       where the event integrators stop: the node kink flags and the held
 *                    segments between the stops;
 *   gk_zones.c       the contact-zone cuts (gk_zone_cuts) and the cuts of a cell;
 *   gk_temperature.c the temperature axis;
 *   gk_envelope.c    the verified envelope.
 *
 * The calls between them run one way: gearkernel.c calls gk_pair.h, which calls gk_lookup.h
 * and gk_stops.c; gk_model.c / gk_temperature.c call gk_stops.c, which calls gk_zones.c;
 * gk_lookup.h and this header call nothing.  The internal
 * functions are prefixed gki_.
 */
#ifndef GK_INTERNAL_H
#define GK_INTERNAL_H

#include <math.h>
#include <stddef.h>

#include "gearkernel.h"

/* the right-hand side and its lookups are inlined into the integrator loops
 * (inlining changes no result: every operation stays as written) */
#if defined(__GNUC__) || defined(__clang__)
#define GK_INLINE static inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define GK_INLINE static __forceinline
#else
#define GK_INLINE static inline
#endif

static inline int gki_finite_pos(double v) { return isfinite(v) && v > 0.0; }

/* |s| below 2^52: a cell index and s - index are exact in doubles and fit a long long */
#define GK_CELL_LIMIT 4503599627370496.0

/* The mode the event integrators hold during each RK4 step (docs/model.md "rk4_kink"):
 * the table cell nd and, per pair, region reg, elastobacklash sub-mode sub, contact_zone
 * flag kpos, and the held segment between two stops. */
typedef struct {
    double nd;                       /* global cell index (integer value) */
    double lo, hi;                   /* held segment [lo, hi): global node indices (rk4_kink: nd, nd + 1) */
    int i0, i1;
    int reg[GK_KINK_MAX_SLOTS];      /* 1 drive, -1 back, 0 separated */
    int sub[GK_KINK_MAX_SLOTS];      /* 0 two (2 fc), 1 sum (fc + fd), 2 zero */
    int kpos[GK_KINK_MAX_SLOTS];     /* contact_zone: k > 0 inside the cell */
    int zsel[GK_KINK_MAX_SLOTS];     /* side of a contact-zone cut held in the cell (gki_zone_sel) */
    double cl, ch;                   /* rk4_seg: floor(lo), ceil(hi) - 1 (the cells of the segment) */
    /* rk4_seg: the table values of every pair at theta1 = fth read by the last seg_end, and
     * fsal = 1 when the substep ended there with the segment [flo, fhi) and the mode unchanged
     * (seg_first reuses them: the same lookup) */
    int fsal;
    double fth, flo, fhi;
    double fkv[GK_KINK_MAX_SLOTS], fev[GK_KINK_MAX_SLOTS], fes[GK_KINK_MAX_SLOTS], fbv[GK_KINK_MAX_SLOTS];
} gk_mode;

/* node index (n mod N) of global node n (an integer value) */
GK_INLINE int gki_node_index(int N, double n)
{
    double r = n - (double)N * floor(n / (double)N);
    int i0 = (int)r;
    if (i0 < 0) i0 = 0;
    if (i0 >= N) i0 = N - 1;
    return i0;
}

/* the nodes i0, i1 of the held cell nd */
GK_INLINE void gki_cell_nodes(gk_mode *md, int N)
{
    double r = md->nd - (double)N * floor(md->nd / (double)N);
    int i0 = (int)r;
    if (i0 < 0) i0 = 0;
    if (i0 >= N) i0 = N - 1;
    md->i0 = i0;
    md->i1 = (i0 + 1 == N) ? 0 : i0 + 1;
}

/* ------------------------------------------------------------- gk_stops.c */
/* the node kink flags of m (gearkernel.h "rk4_node"), after any change of its tables or cuts */
GK_API void gki_node_flags(gk_model *m);
/* the held segment at a step start (theta1 = th, cell md->nd) and across its end (up) or start */
GK_API void gki_seg_start(const gk_model *m, gk_mode *md, int node, double om, double th);
GK_API void gki_seg_cross(const gk_model *m, gk_mode *md, int up, int node);
/* the side of every pair's contact-zone cut held in cell md->nd of the segment */
GK_API void gki_zone_sel(const gk_model *m, gk_mode *md);

/* ------------------------------------------------------------- gk_zones.c */
/* the contact-zone cuts of cell i0 over all slots: the smallest above f (at or above with
 * incl) and below 1, 2.0 for none; the largest below f (at or below with incl) and above 0,
 * -1.0 for none */
GK_API double gki_cut_above(const gk_model *m, int i0, double f, int incl);
GK_API double gki_cut_below(const gk_model *m, int i0, double f, int incl);

#endif /* GK_INTERNAL_H */
