"""Contact-stiffness models of a tooth pair, selectable per scene (``[mesh] contact_model``).

A contact model gives the contact stiffness k_l (N/m) of one face-width slice
of one tooth pair at one meshing position -- the k_l of seed 000 eq 13,
k_tooth^i = 1/(1/k_l + 1/k_tp + 1/k_tg).  Every model has the same signature

    model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness

with flat arrays of equal length (one entry per request):

* ``s_m``: LOA position of the contact (m from N1; the local curvature and the
  entrainment speed follow from it, :func:`gearfmu.ehl.mesh_film.contact_kinematics`);
* ``slice_index``: face-width slice 0 .. NS-1 (roughness differs per slice);
* ``w_N_per_m``: load per unit length of the slice (N/m) from the loaded mesh.

``env`` carries the pair, geometry, pinion speed, lubricant, roughness, slice
width and the executor settings.  The result holds k (N/m per slice), the
number of solves and a list of failures (position, slice, film parameter,
reason).  Registry: :data:`CONTACT_MODELS`; :func:`register_contact_model`
adds one (seed 001's 'fractal_mixed' plugs in here the same way).

Models here:

* ``hertz``: Yang & Sun's load-independent line-contact stiffness
  (:func:`gearfmu.contact.hertz_stiffness_N_per_m`), seed 000's reference case.
* ``smooth_ehl``: oil-film stiffness of seed 000 eq 8-9 from a smooth
  line-contact EHL solve (seed 000 eq 2-7); slices with equal loads are
  identical, so one solve per distinct (position, load).
* ``rough_ehl``: the same with the W-M fractal roughness of both flanks per
  slice (seed 000 eq 1, 3; :mod:`gearfmu.ehl.mesh_film`).  Where the rough
  film collapses (FilmCollapseError) or the solver stalls (EHLConvergenceError,
  which happens at film parameters lambda = h_min/sigma below about 3), the
  policy ``RoughnessSpec.on_failure`` decides: ``"hertz"`` (default) uses the
  Hertz stiffness of that slice and records the failure (provenance + one
  warning) -- seed 000 section 5.1 notes that at high roughness the mesh
  stiffness approaches the Hertz value; ``"error"`` raises
  :class:`ContactModelError` naming the position, the slice and lambda.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional

import numpy as np

from .contact import hertz_stiffness_N_per_m, reduced_modulus_Pa


class ContactModelError(ValueError):
    """Bad contact-model input, or a film failure under ``on_failure = "error"``."""


@dataclass(frozen=True)
class RoughnessSpec:
    """W-M flank roughness (seed 000 eq 1).  ``D`` fractal dimension, ``G_m``
    characteristic scale (m; Table 2's G read in mm, docs/ehl.md), ``seed``
    of the random phases, ``f_max_per_m`` band limit (1/m), ``level`` the
    Table 2 level it came from (0 = custom), ``on_failure`` 'hertz' | 'error'."""

    D: float
    G_m: float
    seed: int = 2022
    f_max_per_m: float = 1e4
    level: int = 0
    on_failure: str = "hertz"

    @staticmethod
    def from_level(level: int, **kw) -> "RoughnessSpec":
        """Seed 000 Table 2 level 1-4 (:data:`gearfmu.roughness.SEED000_LEVELS`)."""
        from .roughness import SEED000_LEVELS

        if level not in SEED000_LEVELS:
            raise ContactModelError(f"level={level!r}: seed 000 Table 2 has levels 1-4")
        lv = SEED000_LEVELS[level]
        return RoughnessSpec(D=lv.D, G_m=lv.G_m, level=int(level), **kw)


@dataclass
class ContactEnvironment:
    """Inputs shared by all requests (SI).  ``omega1_rad_s`` pinion speed;
    lubricant eta0 (Pa s, at the oil temperature), alpha (1/Pa), rho0 (kg/m^3)
    (None for 'hertz'); ``n_slices`` and ``width_m`` of a slice; ``roughness``
    for 'rough_ehl'; ``executor`` / ``max_workers`` / ``progress`` for the EHL
    solves; ``ehl_nodes``: EHL grid nodes (None: the solver's choice)."""

    pair: object
    geom: object
    omega1_rad_s: float
    n_slices: int
    width_m: float
    eta0_Pas: Optional[float] = None
    alpha_Pa_inv: Optional[float] = None
    rho0_kg_m3: Optional[float] = None
    roughness: Optional[RoughnessSpec] = None
    executor: object = None
    max_workers: Optional[int] = None
    progress: bool = False
    ehl_nodes: Optional[int] = None
    _flanks: object = field(default=None, repr=False)

    def film_environment(self):
        from .ehl.mesh_film import FilmEnvironment

        for name in ("eta0_Pas", "alpha_Pa_inv", "rho0_kg_m3"):
            v = getattr(self, name)
            if v is None or not math.isfinite(v) or v < 0 or (v == 0 and name != "alpha_Pa_inv"):
                raise ContactModelError(f"{name}={v!r}: the EHL contact models need a lubricant "
                                        "(eta0 > 0, alpha >= 0, rho0 > 0)")
        return FilmEnvironment(E_prime_Pa=2.0 * reduced_modulus_Pa(self.pair), eta0_Pas=self.eta0_Pas,
                               alpha_Pa_inv=self.alpha_Pa_inv, rho0_kg_m3=self.rho0_kg_m3,
                               width_m=self.width_m, n_nodes=self.ehl_nodes)

    def flanks(self):
        """The sampled flank roughness (made once, cached)."""
        if self._flanks is None:
            from .ehl.mesh_film import make_flank_roughness

            r = self.roughness
            if r is None:
                raise ContactModelError("roughness: 'rough_ehl' needs a RoughnessSpec")
            self._flanks = make_flank_roughness(self.geom, r.D, r.G_m, self.n_slices, r.seed,
                                                f_max_per_m=r.f_max_per_m)
        return self._flanks


@dataclass
class ContactStiffness:
    """Result of a contact model: ``k_N_per_m`` per request (N/m per slice),
    ``solves`` (EHL solves run), ``failures`` (dicts with s_m, slice, w_N_per_m,
    status, film_parameter, message), ``fallbacks`` (how many used Hertz)."""

    k_N_per_m: np.ndarray
    solves: int = 0
    failures: List[dict] = field(default_factory=list)
    fallbacks: int = 0


@dataclass(frozen=True)
class ContactModel:
    """A registered model: ``fn(env, s_m, slice_index, w_N_per_m) -> ContactStiffness``;
    ``load_dependent``: k depends on w (the tables then get a torque axis);
    ``needs_lubricant``."""

    name: str
    fn: Callable
    load_dependent: bool
    needs_lubricant: bool
    doc: str = ""


def _check(env, s_m, slice_index, w):
    s = np.asarray(s_m, dtype=float).ravel()
    n = np.asarray(slice_index).ravel().astype(int)
    w = np.asarray(w, dtype=float).ravel()
    if not (s.shape == n.shape == w.shape):
        raise ContactModelError("s_m, slice_index, w_N_per_m: need equal lengths")
    if np.any(~np.isfinite(s)):
        raise ContactModelError("s_m: contact positions must be finite")
    if np.any(~np.isfinite(w)) or np.any(w <= 0):
        raise ContactModelError("w_N_per_m: slice loads must be finite and > 0 (N/m)")
    if np.any(n < 0) or np.any(n >= env.n_slices):
        raise ContactModelError(f"slice_index: must lie in [0, {env.n_slices})")
    return s, n, w


def hertz_model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness:
    """Yang & Sun Hertz stiffness pi E* width / 2 for every request (N/m)."""
    s, n, w = _check(env, s_m, slice_index, np.ones(np.size(s_m)) if w_N_per_m is None else w_N_per_m)
    return ContactStiffness(np.full(s.shape, hertz_stiffness_N_per_m(env.pair, env.width_m)))


def _key(x: float) -> float:
    return float(f"{x:.10g}")


def smooth_ehl_model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness:
    """Smooth-film stiffness (seed 000 eq 2-9) per request; one solve per distinct (s, w)."""
    from .ehl.mesh_film import contact_kinematics, solve_films

    s, n, w = _check(env, s_m, slice_index, w_N_per_m)
    fenv = env.film_environment()
    keys = [(_key(a), _key(b)) for a, b in zip(s, w)]
    uniq = list(dict.fromkeys(keys))
    su = np.array([k[0] for k in uniq])
    R, u, _ = contact_kinematics(env.geom, su, env.omega1_rad_s)
    reqs = [(float(R[i]), float(u[i]), k[1], None) for i, k in enumerate(uniq)]
    outs = solve_films(fenv, reqs, executor=env.executor, max_workers=env.max_workers,
                       progress=env.progress, label="smooth EHL films")
    bad = [(uniq[i], o) for i, o in enumerate(outs) if o.status != "ok"]
    if bad:
        (sb, wb), o = bad[0]
        raise ContactModelError(f"smooth EHL film failed ({o.status}) at s = {sb * 1e3:.4f} mm, "
                                f"w = {wb:.4g} N/m ({len(bad)} of {len(uniq)} solves): {o.message}")
    kmap = {k: outs[i].k_N_per_m for i, k in enumerate(uniq)}
    return ContactStiffness(np.array([kmap[k] for k in keys]), solves=len(uniq))


def rough_ehl_model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness:
    """Rough-film stiffness per request (roughness of the request's slice at its
    position); failures follow ``env.roughness.on_failure`` (module doc)."""
    from .ehl.mesh_film import contact_kinematics, involute_arc_length_m, solve_films

    s, n, w = _check(env, s_m, slice_index, w_N_per_m)
    spec = env.roughness
    if spec is None:
        raise ContactModelError("roughness: 'rough_ehl' needs a RoughnessSpec (scene [roughness])")
    if spec.on_failure not in ("hertz", "error"):
        raise ContactModelError(f"on_failure={spec.on_failure!r}: must be 'hertz' or 'error'")
    fenv = env.film_environment()
    fl = env.flanks()
    keys = [(_key(a), int(b), _key(c)) for a, b, c in zip(s, n, w)]
    uniq = list(dict.fromkeys(keys))
    su = np.array([k[0] for k in uniq])
    wu = np.array([k[2] for k in uniq])
    R, u, _ = contact_kinematics(env.geom, su, env.omega1_rad_s)
    a1 = involute_arc_length_m(env.geom.roll_length_at(1, su), env.geom.rb1_m)
    a2 = involute_arc_length_m(env.geom.roll_length_at(2, su), env.geom.rb2_m)
    # Hertz half width b = sqrt(8 w R / (pi E')): the roughness is sampled on [-5b, 2b]
    b = np.sqrt(8.0 * wu * R / (math.pi * fenv.E_prime_Pa))
    reqs = []
    for i, (sk, nk, wk) in enumerate(uniq):
        x = np.linspace(-5.0 * b[i], 2.0 * b[i], 2801)
        reqs.append((float(R[i]), float(u[i]), wk, (x, fl.composite_m(nk, float(a1[i]), float(a2[i]), x))))
    outs = solve_films(fenv, reqs, executor=env.executor, max_workers=env.max_workers,
                       progress=env.progress, label="rough EHL films")
    kh = hertz_stiffness_N_per_m(env.pair, env.width_m)
    kmap, failures = {}, []
    for i, o in enumerate(outs):
        if o.status == "ok":
            kmap[uniq[i]] = o.k_N_per_m
            continue
        sk, nk, wk = uniq[i]
        lam = o.film_parameter
        if not math.isfinite(lam):  # stall: lambda from the smooth film at this point
            from .ehl.mesh_film import solve_slice_film
            sm = solve_slice_film(fenv, float(R[i]), float(u[i]), wk)
            x, z = reqs[i][3]
            band = np.abs(x) <= b[i]
            sig = float(np.std(z[band]))
            lam = sm.h_min_m / sig if (sm.status == "ok" and sig > 0) else float("nan")
        failures.append(dict(s_m=sk, slice=nk, w_N_per_m=wk, status=o.status, film_parameter=lam,
                             message=o.message[:160]))
        kmap[uniq[i]] = kh
    if failures and spec.on_failure == "error":
        f0 = failures[0]
        raise ContactModelError(
            f"rough EHL film {f0['status']} at s = {f0['s_m'] * 1e3:.4f} mm (LOA from N1), slice "
            f"{f0['slice']}, film parameter lambda = h_min/sigma = {f0['film_parameter']:.3g} "
            f"({len(failures)} of {len(uniq)} solves failed; roughness level {spec.level}); "
            f"set on_failure = 'hertz' to fall back to Hertz contact there")
    return ContactStiffness(np.array([kmap[k] for k in keys]), solves=len(uniq), failures=failures,
                            fallbacks=len(failures))


#: name -> :class:`ContactModel`
CONTACT_MODELS: Dict[str, ContactModel] = {}


def register_contact_model(name: str, fn: Callable, *, load_dependent: bool, needs_lubricant: bool,
                           doc: str = "") -> ContactModel:
    """Add (or replace) a contact model under ``name`` (see the module doc for ``fn``)."""
    if not isinstance(name, str) or not name:
        raise ContactModelError(f"name={name!r}: must be a non-empty string")
    m = ContactModel(name, fn, bool(load_dependent), bool(needs_lubricant), doc)
    CONTACT_MODELS[name] = m
    return m


register_contact_model("hertz", hertz_model, load_dependent=False, needs_lubricant=False,
                       doc="Yang & Sun (1985) Hertz line-contact stiffness")
register_contact_model("smooth_ehl", smooth_ehl_model, load_dependent=True, needs_lubricant=True,
                       doc="seed 000 eq 8-9 film stiffness of the smooth EHL line contact")
register_contact_model("rough_ehl", rough_ehl_model, load_dependent=True, needs_lubricant=True,
                       doc="seed 000 eq 8-9 film stiffness with W-M roughness per slice")


def _fractal_mixed(env, s_m, slice_index, w_N_per_m):
    """Seed 001 K_n = K_s + K_l (:func:`gearfmu.fractal_contact.fractal_mixed_model`)."""
    from .fractal_contact import fractal_mixed_model

    return fractal_mixed_model(env, s_m, slice_index, w_N_per_m)


register_contact_model("fractal_mixed", _fractal_mixed, load_dependent=True, needs_lubricant=True,
                       doc="seed 001 fractal mixed-lubrication stiffness K_s + K_l")


def get_contact_model(name: str) -> ContactModel:
    """The registered model ``name`` or a :class:`ContactModelError` listing the known ones."""
    try:
        return CONTACT_MODELS[name]
    except KeyError:
        raise ContactModelError(f"contact_model={name!r}: not available; known: "
                                f"{', '.join(sorted(CONTACT_MODELS))}") from None


def environment_from_scene(scene, geom=None, **kw) -> ContactEnvironment:
    """A :class:`ContactEnvironment` from a scene (lubricant at its temperature,
    the scene's pinion speed, slices and ``[roughness]``); ``kw`` overrides fields."""
    from .geometry import pair_geometry

    geom = pair_geometry(scene.pair) if geom is None else geom
    pair = scene.pair
    ns = int(scene.mesh.slices)
    lub = scene.lubricant
    rough = None
    ro = getattr(scene, "roughness", None)
    if ro is not None:
        rough = ro if isinstance(ro, RoughnessSpec) else RoughnessSpec(
            D=ro.D, G_m=ro.G_m, seed=ro.seed, f_max_per_m=ro.f_max_per_m, level=ro.level,
            on_failure=ro.on_failure)
    elif scene.mesh.contact_model == "rough_ehl":
        rough = RoughnessSpec.from_level(1)
    args = dict(pair=pair, geom=geom, omega1_rad_s=float(scene.operating.speed_rad_s), n_slices=ns,
                width_m=min(pair.pinion.face_width_m, pair.gear.face_width_m) / ns,
                eta0_Pas=None if lub is None else lub.dynamic_viscosity_Pas,
                alpha_Pa_inv=None if lub is None else lub.pressure_viscosity_Pa_inv,
                rho0_kg_m3=None if lub is None else lub.density_kg_m3, roughness=rough)
    args.update(kw)
    return ContactEnvironment(**args)


# ---------------------------------------------------------------- sliced TVMS with a contact model
def tooth_compliances(pair, geom, s_m, width_m: float):
    """(c_teeth, c_found_pinion, c_found_gear) in m/N for one slice of width
    ``width_m`` at LOA positions ``s_m`` (any shape, NaN = out of contact):
    c_teeth = 1/k_tp + 1/k_tg (bending, shear, axial of both teeth, seed 000
    eq 14-15) and the Sainsot foundation compliances (eq 12), from
    :func:`gearfmu.stiffness.tooth_compliance_m_per_N`.  NaN entries give NaN."""
    from .stiffness import tooth_compliance_m_per_N

    s = np.asarray(s_m, dtype=float)
    flat = s.ravel()
    ok = np.isfinite(flat)
    ct = np.full(flat.shape, np.nan)
    fp = np.full(flat.shape, np.nan)
    fg = np.full(flat.shape, np.nan)
    if np.any(ok):
        cp = tooth_compliance_m_per_N(pair.pinion, geom, 1, flat[ok], width_m)
        cg = tooth_compliance_m_per_N(pair.gear, geom, 2, flat[ok], width_m)
        ct[ok] = cp["bending"] + cp["shear"] + cp["axial"] + cg["bending"] + cg["shear"] + cg["axial"]
        fp[ok], fg[ok] = cp["foundation"], cg["foundation"]
    return ct.reshape(s.shape), fp.reshape(s.shape), fg.reshape(s.shape)


def sliced_mesh_stiffness(c_teeth_m_per_N, cf_pinion_m_per_N, cf_gear_m_per_N, k_contact_N_per_m, opts,
                          foundation_lambda=(1.0, 1.0)) -> np.ndarray:
    """Per-pair, per-slice mesh stiffness (N/m), shape (P, NS, N), with a contact
    stiffness that differs per slice and position.

    ``c_*``: (P, N) compliances of one slice (:func:`tooth_compliances`; NaN out
    of contact); ``k_contact_N_per_m``: (P, NS, N) the k_l of seed 000 eq 13
    (the film stiffness in place of Hertz).  k_tooth^i = 1/(1/k_l + c_teeth)
    (eq 13), then the foundation per :func:`gearfmu.stiffness.combine_pairs`
    (independent per pair by default, or seed 000 eq 11), slice by slice."""
    from .stiffness import combine_pairs

    kc = np.asarray(k_contact_N_per_m, dtype=float)
    ct = np.asarray(c_teeth_m_per_N, dtype=float)
    P, NS, N = kc.shape
    if ct.shape != (P, N):
        raise ContactModelError(f"c_teeth_m_per_N: expected shape {(P, N)}, got {ct.shape}")
    inz = np.isfinite(ct)[:, None, :] & (kc > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        kt = np.where(inz, 1.0 / (1.0 / np.where(inz, kc, 1.0) + np.where(inz, ct[:, None, :], 0.0)), 0.0)
    fp = np.broadcast_to(np.nan_to_num(np.asarray(cf_pinion_m_per_N, float))[:, None, :], kc.shape)
    fg = np.broadcast_to(np.nan_to_num(np.asarray(cf_gear_m_per_N, float))[:, None, :], kc.shape)
    shape = (P, NS * N)
    return combine_pairs(kt.reshape(shape), np.ascontiguousarray(fp).reshape(shape),
                         np.ascontiguousarray(fg).reshape(shape), opts, foundation_lambda).reshape(P, NS, N)
