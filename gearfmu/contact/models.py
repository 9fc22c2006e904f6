"""Contact-stiffness models of a tooth pair, selectable per scene (``[mesh] contact_model``).

A contact model gives the contact stiffness k_l (N/m) of one face-width slice
of one tooth pair at one meshing position -- the k_l of Zhao et al. 2022 eq 13,
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
adds one (the 'fractal_mixed' model of Xu, Shi & Fan 2023 plugs in here the same way).  The interface
(:class:`ContactEnvironment`, :class:`RoughnessSpec`, :class:`ContactStiffness`) is in
:mod:`gearfmu.contact.base`, the rough-EHL model and its film grid in
:mod:`gearfmu.contact.rough_ehl`; both are importable from here.

Models here:

* ``hertz``: Yang & Sun's load-independent line-contact stiffness
  (:func:`gearfmu.gear.hertz.hertz_stiffness_N_per_m`), the reference case of Zhao et al. 2022.
* ``smooth_ehl``: oil-film stiffness of Zhao et al. 2022 eq 8-9 from a smooth
  line-contact EHL solve (Zhao et al. 2022 eq 2-7); slices with equal loads are
  identical, so one solve per distinct (position, load).
* ``rough_ehl``: the same with the W-M fractal roughness of both flanks per
  slice (Zhao et al. 2022 eq 1, 3; :mod:`gearfmu.ehl.mesh_film`).  Where the rough
  film parameter Lambda = h_min/sigma (Dowson-Higginson h_min, composite W-M
  sigma; :func:`film_parameter`) lies below ``RoughnessSpec.full_film_parameter``
  (default 3, the full-film limit of Tallian 1967), or the rough film
  collapses (FilmCollapseError) or stalls (EHLConvergenceError), the policy
  ``RoughnessSpec.on_failure`` decides: ``"fractal_mixed"`` (default) uses
  the mixed-lubrication stiffness of Xu, Shi & Fan 2023 K_n = K_s + K_l
  (:mod:`gearfmu.contact.fractal`) there, ``"hertz"`` the Hertz stiffness
  (Zhao et al. 2022 section 5.1: at high roughness the mesh stiffness approaches the
  Hertz value), ``"error"`` raises :class:`ContactModelError` naming the
  position, the slice and Lambda, ``"load_sharing"`` lets film and asperities
  share the load (Johnson, Greenwood & Poon 1972; :func:`load_sharing_stiffness`,
  :mod:`gearfmu.contact.load_sharing`).  Every switched point is recorded.
  Speed: with ``RoughnessSpec.position_nodes`` > 0 (default) the films are
  solved on a grid of contact positions x loads shared by all pair slots and
  interpolated (:class:`RoughFilmGrid`, docs/ehl_mesh.md "Speed").
"""
from __future__ import annotations

from typing import Callable, Dict

import numpy as np

from ..common.progress import progress_bar
from ..gear.hertz import hertz_stiffness_N_per_m, reduced_modulus_Pa
from .fractal import slice_contact_stiffness, FractalMeshOptions, FullContactError
from ..ehl.mesh_film import contact_kinematics, solve_films
from ..gear.stiffness import tooth_compliance_m_per_N, combine_pairs
# the interface and the rough-EHL model, importable from the registry's module as before
from .base import (  # noqa: F401
                   ContactModelError, FULL_FILM_PARAMETER, DEFAULT_FILM_POSITION_NODES, FILM_LOAD_NODE_RATIO,
                   STALL_FILL_MAX_SPAN, FILM_LOAD_NODES, FILM_TRANSIENT_SLICES, FILM_TRANSIENT_REDUCTIONS,
                   FILM_TRANSIENT_START, RoughnessSpec, ContactEnvironment, ContactStiffness, ContactModel,
                   _check, _key, composite_sigma_m, film_parameter)
from .rough_ehl import (  # noqa: F401
                        rough_profile, RoughFilmGrid, fill_stalled_ratio, transient_slices,
                        _transient_node_chunk, transient_node_correction, transient_node_film, _mixed_or_nan,
                        _grid_key, film_grid, film_failure_stiffness, load_sharing_stiffness,
                        rough_ehl_model, _smooth_film_k)


def hertz_model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness:
    """Yang & Sun Hertz stiffness pi E* width / 2 for every request (N/m)."""
    s, n, w = _check(env, s_m, slice_index, np.ones(np.size(s_m)) if w_N_per_m is None else w_N_per_m)
    return ContactStiffness(np.full(s.shape, hertz_stiffness_N_per_m(env.pair, env.width_m)))


def smooth_ehl_model(env: ContactEnvironment, s_m, slice_index, w_N_per_m) -> ContactStiffness:
    """Smooth-film stiffness (Zhao et al. 2022 eq 2-9) per request; one solve per distinct (s, w)."""
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


def fractal_mixed_model(env, s_m, slice_index, w_N_per_m):
    """Contact model 'fractal_mixed' (registry signature of this module):
    K_n = K_s + K_l of Xu, Shi & Fan 2023 per (position, slice load) in place of Hertz.
    Roughness from ``env.roughness`` (D, G_m; default Zhao et al. 2022 Table 2 level 1),
    settings from ``env.fractal`` (a :class:`FractalMeshOptions`) when present.
    Requests whose film parameter lies in the full-film range are recorded in
    ``failures`` with status 'full_film' (the build reports them).  Requests whose
    asperities would reach complete contact (A_r >= A0, :class:`FullContactError`) use the
    Hertz stiffness, recorded with status 'complete_contact' and counted in ``fallbacks``
    (the policy of gearfmu.contact.models for the rough-EHL switch)."""
    s, n, w = _check(env, s_m, slice_index, w_N_per_m)
    spec = env.roughness if env.roughness is not None else RoughnessSpec.from_level(1)
    mo = getattr(env, "fractal", None) or FractalMeshOptions()
    Es = reduced_modulus_Pa(env.pair)
    keys = [(_key(a), _key(c)) for a, c in zip(s, w)]  # slices share D, G: same answer
    uniq = list(dict.fromkeys(keys))
    R, u, _ = contact_kinematics(env.geom, np.array([k[0] for k in uniq]), env.omega1_rad_s)
    kmap, notes, full = {}, [], set()
    for i, (sk, wk) in enumerate(progress_bar(uniq, "fractal contact solves", bool(env.progress), unit="solve",
                                               leave=False)):
        try:
            r = slice_contact_stiffness(spec.D, spec.G_m, float(R[i]), float(u[i]), wk, env.width_m, Es,
                                        env.eta0_Pas, env.alpha_Pa_inv, mo)
        except FullContactError as e:
            kmap[(sk, wk)] = hertz_stiffness_N_per_m(env.pair, env.width_m)
            full.add((sk, wk))
            notes.append(dict(s_m=sk, slice=-1, w_N_per_m=wk, status="complete_contact",
                              film_parameter=float("nan"), used="hertz",
                              message=f"real contact area would reach the nominal area (Hertz used): {e}"))
            continue
        kmap[(sk, wk)] = r["K_n_N_per_m"]
        if r["regime"] == "full_film":
            notes.append(dict(s_m=sk, slice=-1, w_N_per_m=wk, status="full_film",
                              film_parameter=r["film_parameter"],
                              message="film parameter >= 3: full film, the mixed model overstates contact"))
    return ContactStiffness(np.array([kmap[k] for k in keys]), solves=len(uniq), failures=notes,
                            fallbacks=sum(k in full for k in keys))


def _fractal_mixed(env, s_m, slice_index, w_N_per_m):
    """Xu, Shi & Fan 2023 K_n = K_s + K_l (:func:`fractal_mixed_model`)."""
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


# ---------------------------------------------------------------- sliced TVMS with a contact model
def tooth_compliances(pair, geom, s_m, width_m: float):
    """(c_teeth, c_found_pinion, c_found_gear) in m/N for one slice of width
    ``width_m`` at LOA positions ``s_m`` (any shape, NaN = out of contact):
    c_teeth = 1/k_tp + 1/k_tg (bending, shear, axial of both teeth, Zhao et al. 2022
    eq 14-15) and the Sainsot foundation compliances (eq 12), from
    :func:`gearfmu.gear.stiffness.tooth_compliance_m_per_N`.  NaN entries give NaN."""
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
    of contact); ``k_contact_N_per_m``: (P, NS, N) the k_l of Zhao et al. 2022 eq 13
    (the film stiffness in place of Hertz).  k_tooth^i = 1/(1/k_l + c_teeth)
    (eq 13), then the foundation per :func:`gearfmu.gear.stiffness.combine_pairs`
    (independent per pair by default, or Zhao et al. 2022 eq 11), slice by slice."""
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