"""Torque rows of the tables with a load-dependent contact model: the slice stiffness of each row
from the contact model's stiffness at that row's slice loads, iterated with the loaded mesh
(:func:`gearfmu.assembly.load_iteration.iterate_load_sharing`; docs/ehl_mesh.md), for spur pairs and
slice by slice on the normal section of helical pairs (docs/helical.md).  Used by
:func:`gearfmu.assembly.precompute.precompute_tables`.  SI units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
import warnings

import numpy as np

from ..common.executors import make_executor
from ..contact.models import (ContactEnvironment, composite_sigma_m, get_contact_model, tooth_compliances,
                              sliced_mesh_stiffness)
from ..gear.stiffness import helical_slice_compliances, slot_stiffness
from .load_iteration import (LOAD_ITERATION_MAX, LOAD_ITERATION_TOL, UNLOADED_SLICE_LOAD_SHARE,
                             iterate_load_sharing, slice_loads_N)


class PrecomputeInputError(ValueError):
    """Bad input to the table precomputation (names the field and the reason); raised here and by
    :mod:`gearfmu.assembly.precompute`, which exports it."""


def per_slice_stiffness(ss, slices: int, reps: int) -> tuple[np.ndarray, np.ndarray]:
    """(k total (P, N), k per slice (P, NS, N)), N/m, of a slot stiffness ``ss``
    (:func:`gearfmu.gear.stiffness.slot_stiffness`) with ``slices`` face-width slices, tiled
    ``reps`` times over the table period."""
    k = np.asarray(ss.k_N_per_m, dtype=float)
    k_tile = np.tile(k, (1, reps))
    ks = getattr(ss, "k_per_slice_N_per_m", None)
    ks = None if ks is None else np.asarray(ks, dtype=float)
    if ks is not None and ks.ndim == 3:  # slices differ (e.g. rough surfaces)
        k_slice = np.tile(ks, (1, 1, reps))
    else:  # equal slices: split the pair stiffness evenly so totals match exactly
        k_slice = np.repeat((k_tile / slices)[:, None, :], slices, axis=1)
    return k_tile, k_slice


class ContactIteration:
    """Slice stiffness with a load-dependent contact model, iterated with the
    loaded static mesh until the slice loads converge (docs/ehl_mesh.md).  A context manager:
    one process pool for all passes and rows.  ``e`` (P, N): the pair error of the loaded mesh,
    set again by the caller for a helical pair (its stiffness-weighted pair error)."""

    def __init__(self, pair, geom, opts, env, slots, points_per_mesh, reps, e_slot, E, nominal_F):
        self.model = get_contact_model(opts.contact_model)
        self.env, self.opts, self.e, self.E = env, opts, e_slot, E
        ss = slot_stiffness(pair, geom, opts, slots, points_per_mesh)
        self.s = np.tile(ss.s_m, (1, reps))                                  # (P, N)
        self.NS = int(opts.slices)
        self.k_hertz = per_slice_stiffness(ss, self.NS, reps)[1]             # (P, NS, N)
        self.helical = None
        if getattr(geom, "helix_angle_rad", 0.0) != 0.0:  # per-slice normal-section requests (docs/helical.md)
            self.helical = normal_section(pair, geom, env, ss, reps)
            self.env = self.helical.env
            self.s_req = self.helical.s_req_m                                # (P, NS, N)
        else:
            ct, fp, fg = tooth_compliances(pair, geom, ss.s_m, ss.slice_width_m)
            self.ct, self.fp, self.fg = (np.tile(a, (1, reps)) for a in (ct, fp, fg))
            self.s_req = np.broadcast_to(self.s[:, None, :], self.k_hertz.shape)
        self.width = ss.slice_width_m
        self.face = ss.slice_width_m * self.NS
        self.nominal_F = nominal_F
        self.zone = np.isfinite(self.s_req)
        self.solves = 0
        self.records = []
        self._pool = None

    def __enter__(self):
        """Open one local process pool for all passes and rows (unless the
        environment brings an executor or asks for max_workers = 1)."""
        env = self.env
        if env.executor is None and (env.max_workers is None or env.max_workers > 1):
            self._pool = make_executor(max_workers=env.max_workers)
            self.env = replace(env, executor=self._pool.__enter__())
        return self

    def __exit__(self, *exc):
        if self._pool is not None:
            self._pool.__exit__(*exc)
            self.env = replace(self.env, executor=None)
            self._pool = None
        return False

    def set_load_range(self, torques, rb1: float) -> None:
        """Tell the contact model which slice loads (N/m) the rows will ask for: the load floor
        of the lightest row to 1.1 x the largest Hertz static slice load of the heaviest, so that
        a film grid can place its load nodes (contact_models.RoughFilmGrid, docs/ehl_mesh.md)."""
        F = [float(t) / rb1 for t in torques]
        lo = UNLOADED_SLICE_LOAD_SHARE * min(f if f > 0 else self.nominal_F for f in F) / self.face
        hi = max([float(np.max(slice_loads_N(self.k_hertz, self.e, self.E, f)[self.zone], initial=0.0))
                  for f in F if f > 0] + [0.0]) / self.width
        self.env = replace(self.env, film_load_range_N_per_m=(lo, max(1.1 * hi, 1.5 * lo)))

    def k_slice(self, torque_Nm: float, rb1: float):
        """(P, NS, N) slice stiffness of the torque row ``torque_Nm`` (N m): the load-sharing
        iteration (:func:`gearfmu.assembly.load_iteration.iterate_load_sharing`) from the Hertz
        slice loads, the films of the row's slice loads from the contact model."""
        F = torque_Nm / rb1
        F_eval = F if F > 0 else self.nominal_F
        floor = UNLOADED_SLICE_LOAD_SHARE * F_eval / self.face               # N/m
        idx = np.nonzero(self.zone)
        j, n, i = idx
        failures = {}

        def solve(w, redo, _pass):
            res = self.model.fn(self.env, self.s_req[j[redo], n[redo], i[redo]], n[redo], w[redo])
            self.solves += res.solves
            for f in res.failures:
                failures[(f["s_m"], f["slice"])] = f
            if not res.failures:
                return res.k_N_per_m, None
            bad = {(f["s_m"], f["slice"]) for f in res.failures}
            sk = np.array([float(f"{x:.10g}") for x in self.s_req[j, n, i]])
            return res.k_N_per_m, np.array([(a, int(b)) in bad for a, b in zip(sk, n)])

        def mesh_stiffness(kc):
            return (sliced_mesh_stiffness(self.ct, self.fp, self.fg, kc, self.opts) if self.helical is None
                    else normal_section_mesh_stiffness(self.helical, kc, self.opts))

        width = self.width if self.helical is None else self.width * self.helical.contact_fraction[idx]
        ls = iterate_load_sharing(slice_loads_N(self.k_hertz, self.e, self.E, F), self.e, self.E, F, idx, width,
                                  floor, solve, mesh_stiffness, what=f"{self.model.name} at torque {torque_Nm:g} N m")
        by_status = {}
        for f in failures.values():
            by_status[f["status"]] = by_status.get(f["status"], 0) + 1
        self.records.append(dict(torque_Nm=float(torque_Nm), passes=ls.passes, load_change=ls.load_change,
                                 failures=len(failures), failures_by_status=dict(sorted(by_status.items())),
                                 failure_list=list(failures.values())))
        return ls.k_slice_N_per_m


@dataclass(frozen=True)
class NormalSection:
    """Contact-model requests of a helical pair, slice by slice, as arrays (docs/helical.md,
    "Load-dependent contact models"); made by :func:`normal_section`.

    Each slice is a thin spur gear of the transverse section whose stiffness is taken on the
    normal section (:func:`gearfmu.gear.stiffness.helical_slot_stiffness`).  The contact model sees
    the slice as a line contact of length w / cos(beta_b) (the slice's piece of the inclined
    contact line) at the slice's own transverse LOA position and load:

    * radius of curvature in the normal section rho_n = rho_t / cos(beta_b) (ISO 6336-2
      Z_H / Z_beta derivation; Niemann/Winter, Maschinenelemente II, ch. 21): the model's
      geometry is the transverse one with every LOA length (N1N2, A, C, E, the request
      positions) divided by cos(beta_b), so R = s1 s2/(s1 + s2) becomes rho_n;
    * entrainment speed normal to the contact line u_n = u_t cos(beta_b) (CHOICE: the flank
      velocities lie in the transverse plane, the contact line is inclined at beta_b on the
      plane of action, and only the component normal to a line contact enters the 1-D
      Reynolds equation, Johnson 1985, Contact Mechanics, ch. 13): the model's pinion speed is
      omega1 cos^2(beta_b) (with the lengths scaled by 1/cos(beta_b)); sliding likewise;
    * load per unit length of contact line w_n = (F_t / cos beta_b)/(w / cos beta_b) = F_t / w,
      the transverse slice load per face width unchanged (ISO 6336-2: F_bn/l_b);
    * the model's normal stiffness k_n (N/m per contact-line length w/cos(beta_b)) goes in
      series with the normal-section tooth compliances of the slice
      (:func:`gearfmu.gear.stiffness.helical_slice_compliances`, same strip length) and the
      result is turned to the transverse line of action by cos^2(beta_b), exactly as the Hertz
      slice of :func:`gearfmu.gear.stiffness.helical_slot_stiffness` (with the 'hertz' model this
      reproduces that function's slice stiffness to round-off; :func:`normal_section_mesh_stiffness`).

    ``env``: the contact models' environment on the normal section; ``s_req_m`` (P, NS, N): the
    request positions on its line of action (m from N1, NaN out of contact); ``c_teeth_m_per_N``,
    ``cf_pinion_m_per_N``, ``cf_gear_m_per_N`` (P, NS, N): the slices' normal-section compliances,
    divided by ``contact_fraction`` (P, NS, N), the engaged part f of each slice (a partly engaged
    slice is a strip of f w, :func:`gearfmu.gear.stiffness.helical_slot_stiffness`);
    ``cos_beta_b``; ``omega1_rad_s`` and ``width_transverse_m``: the transverse pinion speed and
    slice width."""

    env: ContactEnvironment
    s_req_m: np.ndarray
    c_teeth_m_per_N: np.ndarray
    cf_pinion_m_per_N: np.ndarray
    cf_gear_m_per_N: np.ndarray
    contact_fraction: np.ndarray
    cos_beta_b: float
    omega1_rad_s: float
    width_transverse_m: float


def normal_section(pair, geom, env: ContactEnvironment, ss, reps: int) -> NormalSection:
    """The :class:`NormalSection` of a helical pair: ``geom`` its geometry, ``env`` the contact
    environment of the transverse section, ``ss`` its slot stiffness
    (:func:`gearfmu.gear.stiffness.helical_slot_stiffness`: the slice positions and engaged parts),
    tiled ``reps`` times over the table period."""
    if ss.s_slice_m is None:
        raise PrecomputeInputError("contact_model: helical slot stiffness without slice positions")
    c = math.cos(geom.base_helix_angle_rad)
    s_t = np.asarray(ss.s_slice_m, dtype=float)                                  # (P, NS, n)
    geom_n = replace(geom, loa_length_m=geom.loa_length_m / c, s_start_m=geom.s_start_m / c,
                     s_pitch_m=geom.s_pitch_m / c, s_end_m=geom.s_end_m / c)
    env_n = replace(env, geom=geom_n, omega1_rad_s=env.omega1_rad_s * c * c, width_m=env.width_m / c, _flanks=None)
    on = np.isfinite(s_t)
    ct, fp, fg = (np.full(s_t.shape, np.nan) for _ in range(3))
    if np.any(on):
        ct[on], fp[on], fg[on] = helical_slice_compliances(pair, geom, s_t[on], ss.slice_width_m)
    fr = getattr(ss, "slice_contact_fraction", None)
    fr = np.ones(s_t.shape) if fr is None else np.where(on, np.asarray(fr, dtype=float), 1.0)
    ct, fp, fg = ct / fr, fp / fr, fg / fr
    ct, fp, fg, frac = (np.tile(a, (1, 1, reps)) for a in (ct, fp, fg, fr))      # normal section, m/N
    return NormalSection(env=env_n, s_req_m=np.tile(s_t / c, (1, 1, reps)), c_teeth_m_per_N=ct,
                         cf_pinion_m_per_N=fp, cf_gear_m_per_N=fg, contact_fraction=frac, cos_beta_b=c,
                         omega1_rad_s=float(env.omega1_rad_s), width_transverse_m=float(env.width_m))


def normal_section_mesh_stiffness(section: NormalSection, kc_normal_N_per_m, opts) -> np.ndarray:
    """(P, NS, N) transverse slice stiffness (N/m) from the models' normal contact stiffness
    ``kc_normal_N_per_m`` (P, NS, N): k_t = cos^2(beta_b) / (1/k_n + c_teeth,n), then the foundation
    per :func:`gearfmu.gear.stiffness.combine_pairs` slice by slice (normal-section compliances;
    combine_pairs is homogeneous, so scaling after it equals scaling before)."""
    kc = np.asarray(kc_normal_N_per_m, dtype=float)
    P, NS, N = kc.shape
    flat = (P, NS * N)
    k = sliced_mesh_stiffness(section.c_teeth_m_per_N.reshape(flat), section.cf_pinion_m_per_N.reshape(flat),
                              section.cf_gear_m_per_N.reshape(flat),
                              (kc * section.contact_fraction).reshape(P, 1, NS * N), opts)
    c = section.cos_beta_b
    return (c * c) * k.reshape(P, NS, N)


def normal_section_provenance(section: NormalSection) -> dict:
    """The request mapping of a :class:`NormalSection`, for the tables' provenance ('contact')."""
    c = section.cos_beta_b
    return {"speed_rad_s": section.omega1_rad_s,
            "helical_normal_section": {
                "base_helix_angle_rad": math.acos(c),
                "radius_of_curvature": "rho_t / cos(beta_b)",
                "entrainment_speed": "u_t cos(beta_b)",
                "load_per_contact_line_length": "F_t / w (slice face width w)",
                "contact_line_length_per_slice_m": section.width_transverse_m / c,
                "stiffness_to_transverse": "k_t = k_n cos^2(beta_b)"}}


def contact_provenance(ci, axis_note) -> dict:
    """Provenance of a contact-model run: settings, passes, solves, film failures."""
    env = ci.env
    fails = [f for r in ci.records for f in r["failure_list"]]
    out = {
        "model": ci.model.name, "load_dependent": ci.model.load_dependent,
        "speed_rad_s": env.omega1_rad_s, "eta0_Pas": env.eta0_Pas, "alpha_Pa_inv": env.alpha_Pa_inv,
        "rho0_kg_m3": env.rho0_kg_m3, "ehl_nodes": env.ehl_nodes,
        "load_iteration": {"tol_slice_load_over_F_per_NS": LOAD_ITERATION_TOL, "max_passes": LOAD_ITERATION_MAX,
                           "unloaded_slice_load_share": UNLOADED_SLICE_LOAD_SHARE,
                           "rows": [{k: v for k, v in r.items() if k != "failure_list"} for r in ci.records]},
        "solves": ci.solves,
    }
    if axis_note:
        out["torque_axis_note"] = axis_note
    r = env.roughness
    if r is not None and ci.model.name == "rough_ehl":
        out["roughness"] = {"level": r.level, "D": r.D, "G_m": r.G_m, "seed": r.seed,
                            "f_max_per_m": r.f_max_per_m, "on_failure": r.on_failure,
                            "full_film_parameter": r.full_film_parameter, "position_nodes": r.position_nodes,
                            "composite_sigma_m": composite_sigma_m(r)}
        grid = env.film_grid_summary()
        if grid is not None:
            out["film_grid"] = grid
        out["film_failures"] = len(fails)
        out["film_failures_by_status"] = {st: sum(1 for f in fails if f["status"] == st)
                                          for st in sorted({f["status"] for f in fails})}
        out["film_failures_first"] = [
            {"torque_Nm": rec["torque_Nm"], **f} for rec in ci.records for f in rec["failure_list"]][:20]
        if fails:
            uses = {}
            for f in fails:
                uses[f.get("used", r.on_failure)] = uses.get(f.get("used", r.on_failure), 0) + 1
            out["film_failures_by_use"] = uses
        grid = out.get("film_grid") or {}
        out.update(film_failure_kinds(fails, r, grid.get("stalled_rough_nodes_interpolated", 0)))
        msg = film_failure_line(out, r)
        if msg:
            out["warning"] = msg
            warnings.warn(msg)
    return out


_USE_NAMES = {"fractal_mixed": "seed 001 fractal mixed-lubrication stiffness", "hertz": "Hertz stiffness",
              "load_sharing": "film-asperity load sharing (Johnson, Greenwood & Poon 1972)",
              "smooth_ehl": "smooth film"}


def _kind(points) -> dict:
    lam = [f["film_parameter"] for f in points if np.isfinite(f["film_parameter"])]
    used = {}
    for f in points:
        used[f.get("used", "")] = used.get(f.get("used", ""), 0) + 1
    return {"points": len(points),
            "by_status": {st: sum(1 for f in points if f["status"] == st)
                          for st in sorted({f["status"] for f in points})},
            "lambda_range": [min(lam), max(lam)] if lam else None, "used": used}


def film_failure_kinds(fails, spec, grid_nodes_interpolated: int = 0) -> dict:
    """The (position, slice, torque) points without a rough film, by kind
    (docs/ehl_mesh.md): ``film_mixed_lubrication`` -- film parameter below the
    full-film limit (status 'low_film_parameter'; expected: Zhao et al. 2022's full film
    does not hold there) -- and ``film_solver_failures`` -- the rough film
    failed although the film parameter is in the full-film range (stall,
    collapse, smooth film failed: a defect of the solver), each with its count,
    statuses, film-parameter range and what replaced it; the latter also counts
    the film-grid nodes whose stalled rough film was interpolated from their
    neighbours (``grid_nodes_interpolated``)."""
    mixed = [f for f in fails if f["status"] == "low_film_parameter"]
    solver = [f for f in fails if f["status"] != "low_film_parameter"]
    out = {"film_mixed_lubrication": {**_kind(mixed), "full_film_parameter": spec.full_film_parameter},
           "film_solver_failures": {**_kind(solver), "grid_nodes_interpolated": int(grid_nodes_interpolated)}}
    return out


def film_failure_line(c: dict, spec) -> str:
    """One build line on the points without a rough film, each kind counted
    apart (empty when there are none)."""
    mixed, bad = c["film_mixed_lubrication"], c["film_solver_failures"]
    parts = []

    def used(k):
        return ", ".join(f"{_USE_NAMES.get(u, u)} at {v}" for u, v in sorted(k["used"].items()))

    def rng(k):
        lr = k["lambda_range"]
        return f" (lambda = h_min/sigma {lr[0]:.3g}..{lr[1]:.3g})" if lr else ""

    if mixed["points"]:
        parts.append(f"film parameter below {spec.full_film_parameter:g} (mixed lubrication, expected) at "
                     f"{mixed['points']} (position, slice, torque) points{rng(mixed)}; used there: {used(mixed)}")
    if bad["points"] or bad["grid_nodes_interpolated"]:
        st = ", ".join(f"{k} {v}" for k, v in bad["by_status"].items())
        txt = (f"rough film failed at a full-film lambda (solver failure) at {bad['points']} points"
               + (f" ({st}){rng(bad)}; used there: {used(bad)}" if bad["points"] else ""))
        if bad["grid_nodes_interpolated"]:
            txt += (f"; {bad['grid_nodes_interpolated']} film-grid nodes stalled and took their neighbours' "
                    "rough/smooth ratio")
        parts.append(txt)
    if not parts:
        return ""
    return "rough_ehl: " + "; ".join(parts) + " (tables' provenance 'contact.film_mixed_lubrication', " \
        "'contact.film_solver_failures')"
