"""The rough-EHL contact model (``rough_ehl``) and its film grid.

W-M fractal roughness of both flanks per slice (Zhao et al. 2022 eq 1, 3; :mod:`gearfmu.ehl.mesh_film`).
Where the film parameter Lambda = h_min/sigma lies below ``RoughnessSpec.full_film_parameter``
or the rough film collapses or stalls, ``RoughnessSpec.on_failure`` decides (fractal mixed
lubrication, Hertz, error, film-asperity load sharing; see :mod:`gearfmu.contact.models`).
The films are solved on a grid of contact positions x loads shared by all pair slots and
interpolated (:class:`RoughFilmGrid`, docs/ehl_mesh.md "Speed"), optionally corrected by
transient films (docs/ehl_transient.md section 3).
"""
from __future__ import annotations

import math
from typing import Dict, List
import time

import numpy as np

from ..common.vocabulary import FILM_FAILURE_POLICIES
from ..gear.hertz import hertz_stiffness_N_per_m, reduced_modulus_Pa
from .fractal import FractalInputError, slice_contact_stiffness, FractalMeshOptions
from .load_sharing import LineContactState, asperity_parameters, load_sharing, wm_spectral_moments
from ..ehl.errors import EHLConvergenceError, FilmCollapseError
from ..ehl.mesh_film import (contact_kinematics, solve_films, involute_arc_length_m, _solve_node_chunk,
                             map_chunks)
from ..ehl import transient as ehl_transient
from ..ehl.transient import flank_slice_case
from .base import (FILM_LOAD_NODE_RATIO, FILM_LOAD_NODES, FILM_TRANSIENT_REDUCTIONS, FILM_TRANSIENT_SLICES,
                   FILM_TRANSIENT_START, STALL_FILL_MAX_SPAN, ContactEnvironment, ContactModelError,
                   ContactStiffness, _check, _key, film_parameter)


def rough_profile(env, fenv, fl, s: float, slice_index: int, w: float, R: float):
    """Composite roughness (x, wm(x)) of one slice at LOA position ``s`` for the load ``w``
    (sampled on [-5b, 2b], b the Hertz half-width; module doc of gearfmu.ehl.mesh_film)."""
    a1 = float(involute_arc_length_m(env.geom.roll_length_at(1, s), env.geom.rb1_m))
    a2 = float(involute_arc_length_m(env.geom.roll_length_at(2, s), env.geom.rb2_m))
    b = math.sqrt(8.0 * w * R / (math.pi * fenv.E_prime_Pa))
    x = np.linspace(-5.0 * b, 2.0 * b, 2801)
    return x, fl.composite_m(slice_index, a1, a2, x)


class RoughFilmGrid:
    """Rough-film stiffness on a grid of contact positions x loads, interpolated to any
    (position, slice, load) request (docs/ehl_mesh.md "Speed").

    Positions: ``K`` uniform nodes over the path of contact [A, E] (ends included), shared
    by all pair slots (every tooth carries the same roughness realisation).  Loads:
    geometric nodes w_j = anchor * q^j, :data:`FILM_LOAD_NODES` over
    ``env.film_load_range_N_per_m`` when given (the table builder sets it), else
    anchored at the nominal line load with q = :data:`FILM_LOAD_NODE_RATIO`; columns
    are solved lazily as requests need them (one more on each side for the smooth film).  At each node the smooth film is solved once and every slice's
    rough film is warm-started from it (:func:`gearfmu.ehl.mesh_film.solve_node_films`).
    Interpolation (CHOICE, errors measured in benchmarks/bench_ehl_tables.py):

    * smooth stiffness: log k_s cubic spline in s, cubic Lagrange in log w (4 nodes);
    * rough/smooth ratio r = k_r/k_s per slice: piecewise linear in s and in log w.

    k_rough = k_s * r.  A stalled node takes the ratio interpolated from its converged
    neighbours in position (:func:`fill_stalled_ratio`; counted in :meth:`summary`); a node
    still failed (collapse, smooth failure, stall without close converged neighbours) makes
    every request that uses it (non-zero weight) a failure, which the caller's policy
    handles.  The grid is kept on
    the environment and reused by all load-iteration passes and torque rows."""

    def __init__(self, env: "ContactEnvironment", K: int):
        g = env.geom
        self.K = int(K)
        self.s_nodes = np.linspace(float(g.s_start_m), float(g.s_end_m), self.K)
        self.ds = float(self.s_nodes[1] - self.s_nodes[0])
        rng = env.film_load_range_N_per_m
        if rng is not None:  # FILM_LOAD_NODES geometric nodes over the range the tables need
            lo, hi = float(rng[0]), float(rng[1])
            self.anchor = lo
            self.q = max((hi / lo) ** (1.0 / (FILM_LOAD_NODES - 1)), 1.05)
        else:
            self.anchor = float(env.film_load_anchor_N_per_m or 1e5)
            self.q = FILM_LOAD_NODE_RATIO
        self.NS = int(env.n_slices)
        self.smooth: Dict[int, np.ndarray] = {}     # j -> (K,) smooth k (NaN failed)
        self.smooth_status: Dict[int, list] = {}
        self.ratio: Dict[int, np.ndarray] = {}      # j -> (NS, K) rough/smooth (NaN failed)
        self.status: Dict[int, np.ndarray] = {}     # j -> (NS, K) status strings
        self.mixed: Dict[int, np.ndarray] = {}      # j -> (K,) fractal K_n
        self.solves = 0
        self.rough_solves = 0
        self.stalls_interpolated: List[tuple] = []   # (s_m, slice, w_N_per_m) of filled nodes
        self.key = _grid_key(env)
        # transient film correction (RoughnessSpec.film_transient, docs/ehl_transient.md section 3)
        self.transient_mode = getattr(env.roughness, "film_transient", "off")
        self.transient_reduction = getattr(env.roughness, "film_transient_reduction", FILM_TRANSIENT_REDUCTIONS[0])
        self.transient_slices = transient_slices(self.NS)
        self.transient: Dict[int, dict] = {}        # j -> c per node, statuses, costs
        self.ratio_steady: Dict[int, np.ndarray] = {}
        self.status_steady: Dict[int, np.ndarray] = {}
        self.film_parameter_screen = bool(getattr(env.roughness, "screens_film_parameter", True))

    def w_node(self, j) -> np.ndarray:
        return self.anchor * self.q ** np.asarray(j, dtype=float)

    def _jpos(self, w):
        return np.log(np.asarray(w, float) / self.anchor) / math.log(self.q)

    # ----------------------------------------------------------- solving
    def ensure(self, env, fenv, smooth_j, rough_j):
        """Solve the missing smooth columns ``smooth_j`` and rough columns ``rough_j``."""
        rough_new = sorted(set(int(j) for j in rough_j) - set(self.ratio))
        smooth_new = sorted((set(int(j) for j in smooth_j) | set(rough_new)) - set(self.smooth))
        if not smooth_new and not rough_new:
            return
        film_mode = self.transient_mode == "film"   # no steady rough solve: the node's film is transient
        fl = env.flanks() if rough_new and not film_mode else None
        R, u, _ = contact_kinematics(env.geom, self.s_nodes, env.omega1_rad_s)
        chunks, counts, where = [], [], []
        n_cpu = __import__("os").cpu_count() or 1
        cols = sorted(set(smooth_new) | set(rough_new))
        n_rough_nodes = len(rough_new) * self.K
        # split the slices of a node into groups so that there are >= 4 chunks per CPU
        groups = max(1, min(self.NS, math.ceil(4 * n_cpu / max(n_rough_nodes, 1))))
        per = math.ceil(self.NS / groups)
        for j in cols:
            wj = float(self.w_node(j))
            for k in range(self.K):
                if j in rough_new and not film_mode:
                    for n0 in range(0, self.NS, per):
                        sl = list(range(n0, min(self.NS, n0 + per)))
                        prof = [rough_profile(env, fenv, fl, float(self.s_nodes[k]), n, wj, float(R[k])) for n in sl]
                        chunks.append([(float(R[k]), float(u[k]), wj, prof)])
                        counts.append(1 + len(sl))
                        where.append((j, k, sl))
                else:
                    chunks.append([(float(R[k]), float(u[k]), wj, [])])
                    counts.append(1)
                    where.append((j, k, []))
        res = map_chunks(_solve_node_chunk, fenv, chunks, counts, executor=env.executor,
                         max_workers=env.max_workers, progress=env.progress, label="rough EHL film grid")
        for j in smooth_new:
            self.smooth[j] = np.full(self.K, np.nan)
            self.smooth_status[j] = [""] * self.K
        for j in rough_new:
            self.ratio[j] = np.full((self.NS, self.K), np.nan)
            self.status[j] = np.full((self.NS, self.K), "", dtype=object)
        for (j, k, sl), r in zip(where, res):
            sm, outs = r[0]
            self.solves += 1 + len(outs)
            self.rough_solves += sum(1 for o in outs if not o.status.startswith("smooth "))
            if j in smooth_new:
                self.smooth[j][k] = sm.k_N_per_m if sm.status == "ok" else np.nan
                self.smooth_status[j][k] = sm.status
            for n, o in zip(sl, outs):
                ok = o.status == "ok" and sm.status == "ok"
                self.ratio[j][n, k] = o.k_N_per_m / sm.k_N_per_m if ok else np.nan
                self.status[j][n, k] = o.status if sm.status == "ok" else f"smooth {sm.status}"
        if rough_new and film_mode:
            self._run_transients(env, fenv, rough_new)
            for j in rough_new:
                self._apply_transient(j)
        elif rough_new and self.transient_mode != "off":
            self._run_transients(env, fenv, rough_new)
            for j in rough_new:
                self.ratio_steady[j] = self.ratio[j].copy()
                self.status_steady[j] = self.status[j].copy()
                self._apply_transient(j)
        for j in rough_new:  # stalled nodes: ratio from the converged neighbours in position
            self._fill_stalls(j)

    def _fill_stalls(self, j):
        """Stalled nodes of rough column ``j``: ratio from the converged neighbours in position."""
        for n in range(self.NS):
            stalled = self.status[j][n] == "stall"
            if np.any(stalled):
                row, filled = fill_stalled_ratio(self.s_nodes, self.ratio[j][n], stalled)
                self.ratio[j][n] = row
                for k in np.nonzero(filled)[0]:
                    self.status[j][n, k] = "stall_interpolated"
                    self.stalls_interpolated.append((float(self.s_nodes[k]), int(n), float(self.w_node(j))))

    # ----------------------------------------------------------- transient correction
    def _run_transients(self, env, fenv, cols):
        """Transient runs (:func:`gearfmu.ehl.transient.solve_line_contact_transient`, option A of
        docs/ehl_transient.md: R, u_s, SRR and w frozen at the node, the roughness of both flanks
        moving at u1, u2) on :attr:`transient_slices` at every node of the rough columns ``cols``,
        through the grid's executor; stores per node c = mean over those slices of
        k_transient/k_steady for both time reductions (:func:`transient_node_correction`)."""
        film_mode = self.transient_mode == "film"
        chunks, where = [], []
        for j in cols:
            wj = float(self.w_node(j))
            for k in range(self.K):
                if film_mode and not np.isfinite(self.smooth[j][k]):
                    continue          # no smooth film at the node: no ratio (status 'smooth <status>')
                cases = []
                for n in self.transient_slices:
                    kw = flank_slice_case(env, float(self.s_nodes[k]), wj, int(n))
                    if fenv.n_nodes is not None:
                        kw["n_nodes"] = int(fenv.n_nodes)
                    if film_mode:     # as gearfmu.assembly.direct_tvms: frozen start, smooth start + ramp if it stalls
                        kw["start"] = FILM_TRANSIENT_START
                    cases.append(kw)
                chunks.append(cases)
                where.append((j, k))
        res = map_chunks(_transient_node_chunk, None, chunks, [len(c) for c in chunks],
                         executor=env.executor, max_workers=env.max_workers, progress=env.progress,
                         label="transient film correction")
        for j in cols:
            self.transient[j] = {red: np.full(self.K, np.nan) for red in FILM_TRANSIENT_REDUCTIONS + _FILM_RATIOS}
            self.transient[j].update(status=[""] * self.K, message=[""] * self.K, cpu_s=0.0,
                                     steps=[], cycles_per_step=[])
            if film_mode:
                self.transient[j].update(slice_ratios={red: np.full((len(self.transient_slices), self.K), np.nan)
                                                       for red in FILM_TRANSIENT_REDUCTIONS},
                                         starts=[], rescued_steps=0)
                for k in range(self.K):
                    if not np.isfinite(self.smooth[j][k]):
                        self.transient[j]["status"][k] = f"smooth {self.smooth_status[j][k]}"
                        self.transient[j]["message"][k] = "smooth film failed; no transient run"
        for (j, k), r in zip(where, res):
            t = self.transient[j]
            if film_mode:
                c = transient_node_film(r["cases"], float(self.smooth[j][k]))
                for red in FILM_TRANSIENT_REDUCTIONS:
                    t["slice_ratios"][red][:, k] = c["slice_ratios"][red]
                t["starts"] += [q["start"] for q in r["cases"] if q["status"] == "ok"]
                t["rescued_steps"] += sum(q["rescued_steps"] for q in r["cases"] if q["status"] == "ok")
            else:
                c = transient_node_correction(r["cases"])
            for red in FILM_TRANSIENT_REDUCTIONS + _FILM_RATIOS:
                t[red][k] = c[red]
            t["status"][k] = c["status"]
            t["message"][k] = c["message"]
            t["cpu_s"] += r["cpu_s"]
            t["steps"] += [q["steps"] for q in r["cases"] if q["status"] == "ok"]
            t["cycles_per_step"] += [q["cycles_per_step"] for q in r["cases"] if q["status"] == "ok"]

    def _apply_transient(self, j):
        """'correction': ratio = steady ratio x c of the node (every slice); 'film': ratio = the
        node's transient ratio <k_transient>/k_smooth (every slice).  A node whose transient failed
        is a failed node of every slice (status 'stall' -> the stall fill rule, else the policy)."""
        t = self.transient[j]
        c = t[self.transient_reduction]
        ok = np.array([st == "ok" for st in t["status"]])
        if self.transient_mode == "film":
            self.ratio[j] = np.where(ok[None, :], np.broadcast_to(c[None, :], (self.NS, self.K)), np.nan)
            self.status[j] = np.broadcast_to(np.array(t["status"], dtype=object)[None, :],
                                             (self.NS, self.K)).copy()
            return
        self.ratio[j] = np.where(ok[None, :], self.ratio_steady[j] * c[None, :], np.nan)
        st = self.status_steady[j].copy()
        for k in np.nonzero(~ok)[0]:
            steady_ok = st[:, k] == "ok"
            st[steady_ok, k] = t["status"][k]
        self.status[j] = st

    def set_transient_reduction(self, reduction: str) -> None:
        """Use time reduction ``reduction`` (:data:`FILM_TRANSIENT_REDUCTIONS`; default (b)
        "k_of_means") for the correction of the columns solved so far and later ones, without
        new solves (a study hook: examples/seed000_trends.py reports both)."""
        if reduction not in FILM_TRANSIENT_REDUCTIONS:
            raise ContactModelError(f"reduction={reduction!r}: must be one of "
                                    f"{', '.join(FILM_TRANSIENT_REDUCTIONS)}")
        self.transient_reduction = reduction
        for j in sorted(self.transient):
            wj = float(self.w_node(j))
            self.stalls_interpolated = [q for q in self.stalls_interpolated if q[2] != wj]
            self._apply_transient(j)
            self._fill_stalls(j)

    def ensure_mixed(self, env, js):
        """Xu, Shi & Fan 2023 K_n at the grid nodes of the columns ``js`` (in-process)."""
        new = sorted(set(int(j) for j in js) - set(self.mixed))
        if not new:
            return
        spec = env.roughness
        mo = getattr(env, "fractal", None) or FractalMeshOptions()
        Es = reduced_modulus_Pa(env.pair)
        R, u, _ = contact_kinematics(env.geom, self.s_nodes, env.omega1_rad_s)
        for j in new:
            wj = float(self.w_node(j))
            col = np.full(self.K, np.nan)
            for k in range(self.K):
                col[k] = _mixed_or_nan(spec, float(R[k]), float(u[k]), wj, env, Es, mo)
            self.mixed[j] = col

    # ----------------------------------------------------------- interpolation
    def _s_weights(self, s):
        t = (np.asarray(s, float) - self.s_nodes[0]) / self.ds
        i0 = np.clip(np.floor(t).astype(int), 0, self.K - 2)
        f = np.clip(t - i0, 0.0, 1.0)
        return i0, f

    def columns_for(self, w, cubic: bool):
        """(smooth columns, rough columns) needed by loads ``w``."""
        jp = self._jpos(w)
        j0 = np.floor(jp).astype(int)
        lo, hi = int(j0.min()), int(j0.max())
        rough = set(range(lo, hi + 2))
        smooth = set(range(lo - 1, hi + 3)) if cubic else rough
        return smooth, rough

    def _log_cubic(self, table: Dict[int, np.ndarray], s, w):
        """exp of: cubic spline in s of log(table[j]) at the 4 load nodes around w, then
        cubic Lagrange in log w (NaN where a node used is NaN)."""
        jp = self._jpos(w)
        j0 = np.floor(jp).astype(int)
        out = np.full(jp.shape, np.nan)
        for jj in np.unique(j0):
            m = j0 == jj
            nodes = [jj - 1, jj, jj + 1, jj + 2]
            vals = []
            for j in nodes:
                col = np.log(table[j])
                if np.all(np.isfinite(col)):
                    from scipy.interpolate import CubicSpline  # scipy.interpolate: heavy import, only here
                    vals.append(CubicSpline(self.s_nodes, col)(s[m]))
                else:  # a failed node: piecewise linear, NaN next to it
                    i0, f = self._s_weights(s[m])
                    vals.append(_lin(col[i0], col[i0 + 1], f))
            x = jp[m]
            acc = np.zeros(x.shape)
            for a, ja in enumerate(nodes):
                L = np.ones(x.shape)
                for b_, jb in enumerate(nodes):
                    if b_ != a:
                        L *= (x - jb) / (ja - jb)
                acc += L * vals[a]
            # an outer node that failed (e.g. a smooth film below the load floor): linear in
            # log w between the two nodes around w
            lin = _lin(vals[1], vals[2], np.clip(x - jj, 0.0, 1.0))
            out[m] = np.exp(np.where(np.isfinite(acc), acc, lin))
        return out

    def rough_k(self, s, n, w):
        """Interpolated rough film stiffness (N/m; NaN where a node used failed) and, per
        request, the status of the first failed node used ('' if none)."""
        s = np.asarray(s, float)
        n = np.asarray(n, int)
        ks = self._log_cubic(self.smooth, s, w)
        i0, f = self._s_weights(s)
        jp = self._jpos(w)
        j0 = np.floor(jp).astype(int)
        v = np.clip(jp - j0, 0.0, 1.0)
        r = np.full(s.shape, np.nan)
        st = np.full(s.shape, "", dtype=object)
        for jj in np.unique(j0):
            m = j0 == jj
            ra, rb = self.ratio[jj], self.ratio[jj + 1]
            ca = _lin(ra[n[m], i0[m]], ra[n[m], i0[m] + 1], f[m])
            cb = _lin(rb[n[m], i0[m]], rb[n[m], i0[m] + 1], f[m])
            r[m] = _lin(ca, cb, v[m])
            for j, wt in ((jj, 1.0 - v[m]), (jj + 1, v[m])):
                for kk, wk in ((i0[m], 1.0 - f[m]), (i0[m] + 1, f[m])):
                    bad = (wt > 0) & (wk > 0) & (st[m] == "") & ~np.isfinite(self.ratio[j][n[m], kk])
                    if np.any(bad):
                        sub = st[m]
                        sub[bad] = self.status[j][n[m][bad], kk[bad]]
                        st[m] = sub
        return ks * r, st

    def mixed_k(self, env, s, w):
        """Xu, Shi & Fan 2023 K_n (N/m): log K_n cubic spline in s, linear in log w between the two
        load nodes around w (NaN where a node has no solution)."""
        s = np.asarray(s, float)
        _, cols = self.columns_for(w, cubic=False)
        self.ensure_mixed(env, cols)
        jp = self._jpos(w)
        j0 = np.floor(jp).astype(int)
        v = np.clip(jp - j0, 0.0, 1.0)
        out = np.full(s.shape, np.nan)
        for jj in np.unique(j0):
            m = j0 == jj
            vals = []
            for j in (jj, jj + 1):
                col = np.log(self.mixed[j])
                if np.all(np.isfinite(col)):
                    from scipy.interpolate import CubicSpline  # scipy.interpolate: heavy import, only here
                    vals.append(CubicSpline(self.s_nodes, col)(s[m]))
                else:
                    i0, f = self._s_weights(s[m])
                    vals.append(_lin(col[i0], col[i0 + 1], f))
            out[m] = np.exp(_lin(vals[0], vals[1], v[m]))
        return out

    def summary(self) -> dict:
        bad = int(sum(int(np.sum(~np.isfinite(r))) for r in self.ratio.values()))
        return {"position_nodes": self.K, "s_nodes_m": [float(self.s_nodes[0]), float(self.s_nodes[-1])],
                "load_nodes_N_per_m": [float(self.w_node(j)) for j in sorted(self.smooth)],
                "rough_load_nodes_N_per_m": [float(self.w_node(j)) for j in sorted(self.ratio)],
                "film_solves": self.solves, "rough_film_solves": self.rough_solves,
                "failed_rough_nodes": bad,
                "stalled_rough_nodes_interpolated": len(self.stalls_interpolated),
                "stalled_rough_nodes_interpolated_first": [
                    {"s_m": a, "slice": b, "w_N_per_m": c} for a, b, c in self.stalls_interpolated[:20]],
                "stall_rule": "a stalled rough node takes the rough/smooth ratio interpolated linearly in "
                              "position between the nearest converged nodes of its slice and load column "
                              f"(at most {STALL_FILL_MAX_SPAN} node spacings apart; an end node the adjacent "
                              "node's); otherwise the policy's smooth film",
                "interpolation": "smooth k: cubic spline in s, cubic Lagrange in log w; rough/smooth "
                                 "ratio per slice: linear in s and log w",
                **({"film_transient": self.transient_summary()} if self.transient_mode != "off" else {})}

    def transient_summary(self) -> dict:
        """Provenance of the transient film correction (docs/ehl_transient.md section 3)."""
        t = self.transient
        js = sorted(t)
        failed = [(float(self.s_nodes[k]), float(self.w_node(j)), t[j]["status"][k], t[j]["message"][k])
                  for j in js for k in range(self.K) if t[j]["status"][k] != "ok"]
        steps = [x for j in js for x in t[j]["steps"]]
        cyc = [x for j in js for x in t[j]["cycles_per_step"]]
        extra = {}
        if self.transient_mode == "film":
            sr = [t[j]["slice_ratios"][self.transient_reduction] for j in js]
            spread = [float(np.ptp(a[:, k]) / np.mean(a[:, k])) for a in sr for k in range(a.shape[1])
                      if np.all(np.isfinite(a[:, k]))]
            starts = [x for j in js for x in t[j]["starts"]]
            extra = {"runs_smooth_start": sum(1 for x in starts if x == "smooth"),
                     "rescued_steps": int(sum(t[j]["rescued_steps"] for j in js)),
                     "slice_spread_max": max(spread) if spread else None,
                     "slice_spread_mean": float(np.mean(spread)) if spread else None,
                     "film_parameter_screen": self.film_parameter_screen,
                     "rule": "ratio = mean over the listed slices of k_transient/k_smooth (k_smooth: the grid's "
                             "steady smooth film at the node), the same for every slice; start 'auto' (frozen, "
                             "smooth + roughness ramp where the frozen start stalls); no steady rough solve; a "
                             "node whose transient fails on any of its slices is a failed node (stall: fill rule, "
                             "collapse: the film-failure policy); slice_spread = (max - min)/mean of the "
                             "per-slice ratios of a node"}
        return {"mode": self.transient_mode, "reduction": self.transient_reduction,
                "slices": [int(n) for n in self.transient_slices],
                "nodes": len(js) * self.K, "transient_runs": len(steps),
                "failed_nodes": len(failed),
                "failed_nodes_by_status": {st: sum(1 for f in failed if f[2] == st)
                                           for st in sorted({f[2] for f in failed})},
                "failed_nodes_first": [{"s_m": a, "w_N_per_m": b, "status": c, "message": m}
                                       for a, b, c, m in failed[:10]],
                "c_by_load_node": {f"{float(self.w_node(j)):.6g}": {
                    red: [None if not np.isfinite(v) else float(v) for v in t[j][red]]
                    for red in FILM_TRANSIENT_REDUCTIONS + _FILM_RATIOS} for j in js},
                "worker_cpu_s": float(sum(t[j]["cpu_s"] for j in js)),
                "steps_per_run_mean": float(np.mean(steps)) if steps else None,
                "cycles_per_step_mean": float(np.mean(cyc)) if cyc else None,
                "rule": "c = mean over the listed slices of k_transient/k_steady (k_steady: the run's own "
                        "steady frozen-roughness start); every slice's steady rough/smooth ratio x c; a node "
                        "whose transient fails on any of its slices is a failed node (stall: fill rule)",
                **extra}


def fill_stalled_ratio(s_nodes, ratio, stalled, max_span: int = STALL_FILL_MAX_SPAN):
    """Stall replacement rule of the film grid (CHOICE, docs/ehl_mesh.md "Speed").

    ``ratio``: rough/smooth film-stiffness ratios of one slice and load column at the
    position nodes ``s_nodes`` (m, uniform), NaN where not converged; ``stalled``: bool
    mask of the nodes whose rough solve stalled (collapses and smooth failures are not
    replaced: a collapse is physics, not a solver limit).  A stalled interior node gets
    the linear interpolation in s between the nearest converged nodes on both sides when
    they are at most ``max_span`` node spacings apart; a stalled end node (no converged
    node on one side) the ratio of its converged neighbour.  Reason: between the nodes
    the grid already uses this piecewise-linear trend of the ratio (the position-to-
    position roughness effect is not resolved, docs/ehl_mesh.md), so the stalled node
    gets the value the grid would give there without it, instead of ratio 1 (the smooth
    film), which is biased (a converged level-2 rough film is ~2 % stiffer than smooth
    on average).  Returns (new ratio row, bool mask of filled nodes)."""
    s = np.asarray(s_nodes, float)
    r = np.array(ratio, dtype=float)
    st = np.asarray(stalled, bool)
    if r.shape != s.shape or st.shape != s.shape:
        raise ContactModelError(f"fill_stalled_ratio: ratio {r.shape} and stalled {st.shape} must have "
                                f"the shape of s_nodes {s.shape}")
    good = np.nonzero(np.isfinite(r))[0]
    filled = np.zeros(s.shape, bool)
    out = r.copy()
    for k in np.nonzero(st & ~np.isfinite(r))[0]:
        lo = good[good < k]
        hi = good[good > k]
        if lo.size and hi.size:
            a, b = lo[-1], hi[0]
            if b - a <= max_span:
                f = (s[k] - s[a]) / (s[b] - s[a])
                out[k] = (1.0 - f) * r[a] + f * r[b]
                filled[k] = True
        elif (lo.size and k - lo[-1] == 1 and k == s.size - 1) or (hi.size and hi[0] - k == 1 and k == 0):
            out[k] = r[lo[-1]] if lo.size else r[hi[0]]
            filled[k] = True
    return out, filled


def transient_slices(n_slices: int, count: int = FILM_TRANSIENT_SLICES) -> np.ndarray:
    """Slices run in time at each film-grid node for the transient correction (CHOICE,
    docs/ehl_transient.md section 3): ``count`` slices spread evenly over the face,
    round(linspace(0, NS - 1, count)); every slice when NS <= count."""
    ns = int(n_slices)
    if ns <= count:
        return np.arange(ns)
    return np.unique(np.round(np.linspace(0.0, ns - 1.0, int(count))).astype(int))


def _transient_node_chunk(_env, cases):
    """Worker: one film-grid node's transient runs (keyword arguments of
    :func:`gearfmu.ehl.transient.solve_line_contact_transient`, one per slice).  Per run:
    status 'ok' | 'stall' | 'collapse', k_steady (the run's steady frozen-roughness start,
    Zhao et al. 2022 eq 8 on |x| <= b) and the time reductions (a) and (b) of docs/ehl_transient.md
    section 3 over the default window (after the wash-out)."""

    t0 = time.process_time()
    out = []
    for kw in cases:
        try:
            # looked up at call time, so a substitute set on the module is used
            r = ehl_transient.solve_line_contact_transient(**kw)
        except FilmCollapseError as exc:
            out.append({"status": "collapse", "message": str(exc)[:300]})
            continue
        except EHLConvergenceError as exc:
            out.append({"status": "stall", "message": str(exc)[:300]})
            continue
        red = r.film_stiffness_reductions()
        out.append({"status": "ok", "message": "", "k_steady_N_per_m": float(r.k_film_N_per_m[0]),
                    "k_of_means": red["k_of_means_N_per_m"], "mean_of_k": red["k_mean_of_k_N_per_m"],
                    "steps": int(r.T.size - 1), "cycles_per_step": float(r.cycles[1:].mean()),
                    "h_central_ratio": red["h_central_mean_m"] / float(r.h_central_m[0]),
                    "h_mean_ratio": red["h_mean_m"] / float(r.h_mean_m[0]), "start": r.start,
                    "rescued_steps": int(np.count_nonzero(r.rescued)) if r.rescued is not None else 0})
    return {"cases": out, "cpu_s": time.process_time() - t0}


def transient_node_correction(cases) -> dict:
    """Transient film correction of one grid node from its runs (outputs of
    :func:`_transient_node_chunk`): c = mean over the slices of <k_transient>/k_steady per time
    reduction (docs/ehl_transient.md section 3 "last row"; k_steady is the run's own steady
    frozen-roughness start, so c measures only the motion of the roughness).  Any failed run
    fails the node: status of the first failure, c NaN."""
    bad = [q for q in cases if q["status"] != "ok"]
    if bad or not cases:
        q = bad[0] if bad else {"status": "stall", "message": "no transient run"}
        return {**{red: float("nan") for red in FILM_TRANSIENT_REDUCTIONS + _FILM_RATIOS},
                "status": q["status"], "message": q["message"]}
    return {**{red: float(np.mean([q[red] / q["k_steady_N_per_m"] for q in cases]))
               for red in FILM_TRANSIENT_REDUCTIONS},
            **{h: float(np.mean([q.get(h, np.nan) for q in cases])) for h in _FILM_RATIOS},
            "status": "ok", "message": ""}


def transient_node_film(cases, k_smooth_N_per_m: float) -> dict:
    """Film ratio of one grid node under ``film_transient = "film"`` from its transient runs
    (outputs of :func:`_transient_node_chunk`, start 'auto'): per time reduction (b)
    k_of_means = A B(<p_m>)/<h_m> and (a) mean_of_k = <A B(p_m)/h_m> (Zhao et al. 2022 eq 8 on the
    window after ramp + wash-out, docs/ehl_transient.md section 3), ratio = mean over the run
    slices of k_transient / ``k_smooth_N_per_m`` (the grid's steady smooth film at the same
    node, same EHL grid).  CHOICE: one ratio for every slice of the node (the time-averaged
    film varies little between slices: spread measured in docs/ehl_mesh.md "Transient films in
    the tables"); ``slice_ratios`` keeps the per-slice values.  Any failed run fails the node
    (status of the first failure, ratio NaN): a collapse (h <= 0) means no full film."""
    names = FILM_TRANSIENT_REDUCTIONS + _FILM_RATIOS
    bad = [q for q in cases if q["status"] != "ok"]
    if not (math.isfinite(k_smooth_N_per_m) and k_smooth_N_per_m > 0):
        bad = bad or [{"status": "smooth failed", "message": "no smooth film at the node"}]
    if bad or not cases:
        q = bad[0] if bad else {"status": "stall", "message": "no transient run"}
        return {**{red: float("nan") for red in names}, "status": q["status"], "message": q["message"],
                "slice_ratios": {red: np.full(len(cases), np.nan) for red in FILM_TRANSIENT_REDUCTIONS}}
    per = {red: np.array([q[red] / k_smooth_N_per_m for q in cases]) for red in FILM_TRANSIENT_REDUCTIONS}
    return {**{red: float(np.mean(per[red])) for red in FILM_TRANSIENT_REDUCTIONS},
            **{h: float(np.mean([q.get(h, np.nan) for q in cases])) for h in _FILM_RATIOS},
            "status": "ok", "message": "", "slice_ratios": per}


#: film-thickness ratios (window mean over the steady start) reported with the correction:
#: central film and mean film on |x| <= b (the explanation of Figs. 12-13 in Zhao et al. 2022 is a thicker
#: central film on rough surfaces)
_FILM_RATIOS = ("h_central_ratio", "h_mean_ratio")


def _mixed_or_nan(spec, R, u, w, env, Es, mo) -> float:
    """Xu, Shi & Fan 2023 K_n of one slice, NaN where the asperities cannot carry the load on the
    Hertz band (FractalInputError, or a real contact area A_r >= A0)."""
    try:
        r = slice_contact_stiffness(spec.D, spec.G_m, R, u, w, env.width_m, Es, env.eta0_Pas, env.alpha_Pa_inv, mo)
    except FractalInputError:
        return float("nan")
    # A_r >= A0: the asperity model has left its range (complete contact of the band)
    return float(r["K_n_N_per_m"]) if r["real_area_ratio"] < 1.0 else float("nan")


def _lin(a, b, f):
    """(1-f) a + f b without letting a NaN with zero weight through."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    return np.where(f >= 1.0, b, np.where(f <= 0.0, a, (1.0 - f) * a + f * b))


def _grid_key(env) -> tuple:
    r = env.roughness
    return (r.D, r.G_m, r.seed, r.f_max_per_m, r.position_nodes, env.omega1_rad_s, env.n_slices, env.width_m,
            env.eta0_Pas, env.alpha_Pa_inv, env.rho0_kg_m3, env.ehl_nodes, env.film_load_anchor_N_per_m,
            env.film_load_range_N_per_m, id(env.geom), id(env.pair), getattr(r, "film_transient", "off"),
            getattr(r, "film_transient_reduction", FILM_TRANSIENT_REDUCTIONS[0]))


def film_grid(env: "ContactEnvironment") -> RoughFilmGrid:
    """The environment's :class:`RoughFilmGrid` (made once, kept while the settings hold)."""
    g = env._grid
    if g is None or g.key != _grid_key(env):
        g = RoughFilmGrid(env, env.roughness.position_nodes)
        env._grid = g
    return g


def film_failure_stiffness(env: "ContactEnvironment", s_m, slice_index, w_N_per_m) -> np.ndarray:
    """Contact stiffness (N/m) where the full film does not hold, per ``env.roughness.on_failure``:
    'fractal_mixed' Xu, Shi & Fan 2023 K_n = K_s + K_l (on the film grid when ``position_nodes`` > 0,
    else :func:`gearfmu.contact.models.fractal_mixed_model` per request), 'hertz' the Yang &
    Sun Hertz stiffness.  ('error' is raised by the model before this is called.)"""
    s = np.asarray(s_m, float)
    w = np.asarray(w_N_per_m, float)
    pol = env.roughness.on_failure
    if s.size == 0:
        return np.zeros(0)
    if pol == "hertz":
        return np.full(s.shape, hertz_stiffness_N_per_m(env.pair, env.width_m))
    if pol == "load_sharing":
        return load_sharing_stiffness(env, s, w)
    if pol != "fractal_mixed":
        raise ContactModelError(f"on_failure={pol!r}: no fallback stiffness")

    k = film_grid(env).mixed_k(env, s, w) if env.roughness.position_nodes else np.full(s.shape, np.nan)
    bad = ~np.isfinite(k)
    if np.any(bad):  # per request (no grid, or a grid node without a solution)
        # K_n depends on (position, load) only (same D, G and width on every slice): one
        # evaluation per distinct pair (level 4 of the default scene: 4779 requests)
        keys = np.array([_key(a) for a in s[bad]]), np.array([_key(b) for b in w[bad]])
        pairs, inv = np.unique(np.stack(keys, axis=1), axis=0, return_inverse=True)
        R, u, _ = contact_kinematics(env.geom, pairs[:, 0], env.omega1_rad_s)
        mo = getattr(env, "fractal", None) or FractalMeshOptions()
        Es = reduced_modulus_Pa(env.pair)
        vals = np.array([_mixed_or_nan(env.roughness, float(Ri), float(ui), float(wi), env, Es, mo)
                         for Ri, ui, wi in zip(R, u, pairs[:, 1])])
        k[bad] = vals[np.asarray(inv).ravel()]
    # no mixed solution: the load exceeds what the asperities carry on the Hertz band, i.e. the
    # surfaces are in full solid contact there -- Hertz (CHOICE, docs/ehl_mesh.md)
    return np.where(np.isfinite(k), k, hertz_stiffness_N_per_m(env.pair, env.width_m))


def load_sharing_stiffness(env: "ContactEnvironment", s_m, w_N_per_m) -> np.ndarray:
    """Mixed-lubrication stiffness (N/m per slice) by film-asperity load sharing
    (``on_failure = "load_sharing"``; :func:`gearfmu.contact.load_sharing.load_sharing`, Johnson,
    Greenwood & Poon 1972; docs/load_sharing.md): k = k_film + k_asp at the shared separation,
    the film spring being the smooth film's stiffness at the request (film grid when
    ``position_nodes`` > 0, else a smooth solve) times the Zhao et al. 2022 eq 8 ratio at the film's
    share of the load; where the smooth film failed, eq 8 with Moes' film alone.  Summit
    statistics from the W-M moments of both flanks (:func:`gearfmu.contact.load_sharing.wm_spectral_moments`).
    One evaluation per distinct (position, load): the slices share D, G and width."""
    s = np.asarray(s_m, float).ravel()
    w = np.asarray(w_N_per_m, float).ravel()
    if s.size == 0:
        return np.zeros(0)
    spec = env.roughness
    fenv = env.film_environment()
    a = env.alpha_Pa_inv
    asp = asperity_parameters(wm_spectral_moments(spec.D, spec.G_m))
    keys = np.stack([np.array([_key(x) for x in s]), np.array([_key(x) for x in w])], axis=1)
    pairs, inv = np.unique(keys, axis=0, return_inverse=True)
    if spec.position_nodes:
        film_grid(env)   # the smooth films come from the grid's smooth columns, not per request
    ks = _smooth_film_k(env, fenv, pairs[:, 0], pairs[:, 1])
    R, u, _ = contact_kinematics(env.geom, pairs[:, 0], env.omega1_rad_s)
    vals = np.empty(len(pairs))
    for i, (Ri, ui, (_, wi)) in enumerate(zip(R, u, pairs)):
        st = LineContactState(R_m=float(Ri), u_m_per_s=float(ui), w_N_per_m=float(wi),
                              E_prime_Pa=fenv.E_prime_Pa, eta0_Pas=float(env.eta0_Pas),
                              alpha_Pa_inv=float(a), width_m=float(env.width_m))
        k0 = float(ks[i]) if np.isfinite(ks[i]) and ks[i] > 0 else None
        vals[i] = load_sharing(st, asp, k_smooth_N_per_m=k0).k_N_per_m
    return vals[np.asarray(inv).ravel()].reshape(np.shape(s_m))


def rough_ehl_model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness:
    """Rough-film stiffness per request (roughness of the request's slice at its
    position).  Requests with Lambda < ``full_film_parameter`` (:func:`film_parameter`)
    and requests whose rough film fails follow ``env.roughness.on_failure``
    (module doc); they are returned in ``failures`` (s_m, slice, w_N_per_m, status
    'low_film_parameter' | 'stall' | 'collapse' | ..., film_parameter, used, message)."""
    s, n, w = _check(env, s_m, slice_index, w_N_per_m)
    spec = env.roughness
    if spec is None:
        raise ContactModelError("roughness: 'rough_ehl' needs a RoughnessSpec (scene [roughness])")
    if spec.on_failure not in FILM_FAILURE_POLICIES:
        raise ContactModelError(f"on_failure={spec.on_failure!r}: must be one of {', '.join(FILM_FAILURE_POLICIES)}")
    fenv = env.film_environment()
    lam = film_parameter(env, s, w)
    full = lam >= spec.full_film_parameter if spec.screens_film_parameter else np.ones(s.shape, bool)
    k = np.full(s.shape, np.nan)
    status = np.full(s.shape, "low_film_parameter", dtype=object)
    solves = 0
    if np.any(full) and spec.position_nodes:
        g = film_grid(env)
        before = g.solves
        sj, rj = g.columns_for(w[full], cubic=True)
        g.ensure(env, fenv, sj, rj)
        kf, st = g.rough_k(s[full], n[full], w[full])
        k[full] = kf
        status[full] = np.where(np.isfinite(kf), "ok", np.where(st == "", "smooth film failed", st))
        solves = g.solves - before
    elif np.any(full):
        fl = env.flanks()
        idx = np.nonzero(full)[0]
        keys = [(_key(s[i]), int(n[i]), _key(w[i])) for i in idx]
        uniq = list(dict.fromkeys(keys))
        su = np.array([q[0] for q in uniq])
        R, u, _ = contact_kinematics(env.geom, su, env.omega1_rad_s)
        reqs = [(float(R[i]), float(u[i]), q[2], rough_profile(env, fenv, fl, q[0], q[1], q[2], float(R[i])))
                for i, q in enumerate(uniq)]
        outs = solve_films(fenv, reqs, executor=env.executor, max_workers=env.max_workers,
                           progress=env.progress, label="rough EHL films")
        omap = dict(zip(uniq, outs))
        for i, kk in zip(idx, keys):
            o = omap[kk]
            k[i] = o.k_N_per_m if o.status == "ok" else np.nan
            status[i] = o.status
        solves = len(uniq)
    failed = ~np.isfinite(k)
    used = np.full(s.shape, spec.on_failure, dtype=object)
    # a rough solve that stalls or collapses although Lambda is in the full-film range is a limit of
    # the solver, not of the film: under 'fractal_mixed' the smooth film stands in there (the
    # roughness changes a converged film's stiffness by a few % at most, docs/ehl_mesh.md)
    sub = failed & full
    if spec.film_transient == "film":   # the transient film collapsed (h <= 0): no full film -> policy
        sub &= status != "collapse"
    if spec.on_failure in ("fractal_mixed", "load_sharing") and np.any(sub):
        ks = _smooth_film_k(env, fenv, s[sub], w[sub])
        k[sub] = ks
        used[sub] = np.where(np.isfinite(ks), "smooth_ehl", spec.on_failure)
    failures = []
    for i in np.nonzero(failed)[0]:
        st = str(status[i]) or "failed"
        failures.append(dict(s_m=_key(s[i]), slice=int(n[i]), w_N_per_m=_key(w[i]), status=st,
                             film_parameter=float(lam[i]), used=str(used[i]),
                             message=("film parameter below the full-film limit "
                                      f"{spec.full_film_parameter:g}" if st == "low_film_parameter"
                                      else f"rough EHL film {st} (interpolation node or request)")))
    if failures and spec.on_failure == "error":
        f0 = failures[0]
        raise ContactModelError(
            f"rough EHL film: {f0['status']} at s = {f0['s_m'] * 1e3:.4f} mm (LOA from N1), slice "
            f"{f0['slice']}, film parameter lambda = h_min/sigma = {f0['film_parameter']:.3g} "
            f"(full-film limit {spec.full_film_parameter:g}; {len(failures)} of {s.size} requests; roughness "
            f"level {spec.level}); set [roughness] on_film_failure = 'fractal_mixed', 'load_sharing' or 'hertz' to "
            "continue")
    rest = ~np.isfinite(k)
    if np.any(rest):
        k[rest] = film_failure_stiffness(env, s[rest], n[rest], w[rest])
    return ContactStiffness(k, solves=solves, failures=failures, fallbacks=int(np.sum(failed)))


def _smooth_film_k(env, fenv, s, w) -> np.ndarray:
    """Smooth-film stiffness (N/m; NaN where it fails): from the film grid when it exists,
    else one smooth solve per distinct request."""
    if env.roughness.position_nodes and env._grid is not None:
        g = film_grid(env)
        sj, _ = g.columns_for(w, cubic=True)
        g.ensure(env, fenv, sj, [])
        return g._log_cubic(g.smooth, np.asarray(s, float), w)
    keys = [(_key(a), _key(b)) for a, b in zip(s, w)]
    uniq = list(dict.fromkeys(keys))
    R, u, _ = contact_kinematics(env.geom, np.array([q[0] for q in uniq]), env.omega1_rad_s)
    outs = solve_films(fenv, [(float(R[i]), float(u[i]), q[1], None) for i, q in enumerate(uniq)],
                       executor=env.executor, max_workers=env.max_workers, progress=False)
    kmap = {q: (o.k_N_per_m if o.status == "ok" else np.nan) for q, o in zip(uniq, outs)}
    return np.array([kmap[q] for q in keys])
