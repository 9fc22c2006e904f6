"""Tooth, foundation and tooth-pair mesh stiffness (TVMS) of a spur or helical gear pair.

Helical pairs: staggered face-width slices, :func:`helical_slot_stiffness` (docs/helical.md).

Zhao et al. 2022 eq (11)-(15): potential-energy (Yang & Lin 1987; Tian 2004; Chen &
Shao 2011; Sun, Ma et al. 2018 MMT 129 = Zhao et al. 2022 ref [46]) bending, shear and
axial-compression compliances of each tooth of a face-width slice, the
fillet-foundation compliance of Sainsot et al. (2004) (:mod:`gearfmu.gear.foundation`),
Hertz contact (:mod:`gearfmu.gear.hertz`), and the shared-foundation correction of
Ma, Zeng, Feng, Pang & Wen (2016), MMT 98 (Zhao et al. 2022 eq 11).

Tooth model (per gear, a cantilever on the tooth centre line, x = distance
from the gear centre along the centre line, h(x) = half tooth thickness):

* involute part, from max(r_b, r_f) up to the load point, parametrised by
  the roll angle u (rho = r_b sqrt(1 + u^2)): psi(rho) = alpha_2 - inv(alpha_rho),
  x = rho cos psi, h = rho sin psi, alpha_2 = pi/(2z) + 2 x tan(alpha)/z + inv(alpha);
* below the base circle (only when r_f < r_b): CHOICE, the usual straight
  line of constant half thickness h = r_b sin(alpha_2) from x = r_f cos(alpha_3)
  to x = r_b cos(alpha_2), alpha_3 = arcsin(r_b sin(alpha_2)/r_f) (Chen & Shao
  2011, Eng. Fail. Anal. 18; Tian 2004 M.Sc. thesis).
* load F = 1 N normal to the flank at the contact point P (roll angle phi
  = roll length / r_b), alpha_1 = phi - alpha_2 the angle between F and the
  normal to the centre line; P = r_b (cos a1 + phi sin a1, phi cos a1 - sin a1).

  1/k_b = int [cos a1 (x_P - x) - y_P sin a1]^2 / (E I(x)) dx,   I = (2h)^3 w/12
  1/k_s = int 1.2 cos^2 a1 / (G A(x)) dx,                         A = 2 h w
  1/k_a = int sin^2 a1 / (E A(x)) dx,                             G = E/(2(1+nu))

  integrated from the root to x_P by Gauss-Legendre quadrature (Zhao et al. 2022 eq 15,
  which writes the same integrals over the transition curve and the involute).

Foundation: Sainsot's theta_f is the half angle of the tooth at the root circle
between the fillet end points.  CHOICE: taken from the rack-generated root
(tool with tip radius rho_t = c* m/(1 - sin alpha), the full-round tip that
ISO 53 profile A approximates with 0.38 m): the root circle is cut by the flat
tool tip, whose half width is
  u_t = (pi m/4 - x m tan a) - (ha* + c* - x) m tan a - rho_t tan(pi/4 - a/2),
so theta_f = pi/z - u_t/r (a tooth is pi/z wide in half angle on the root
circle minus the half space cut by the tool tip).  The idealised straight-line
root would give theta_f = alpha_3, about 30 % smaller for a 20 deg standard tooth,
which makes the Sainsot term 1.5-2 times softer.  h_f = r_f / r_int; CHOICE when
``GearSpec.hub_radius_m`` is None: r_int = r_f / 2 (h_f = 2).

Mesh: per slice and pair i, k_tooth^i = 1/(1/k_h + 1/k_tp + 1/k_tg) (Zhao et al. 2022
eq 13-14).  Without the shared-foundation correction each pair is
k_i = 1/(1/k_tooth^i + 1/k_fp^i + 1/k_fg^i) (foundation of each tooth loaded by
its own pair only).  With it (Zhao et al. 2022 eq 11, Ma et al. 2016)
k_n = 1/(1/(lambda_p k_fp) + 1/k_tooth + 1/(lambda_g k_fg)),
k_tooth = sum_i k_tooth^i.  CHOICES: (1) the foundation compliances 1/k_f of
eq 11 are the load-weighted means of the per-pair values, weights
k_tooth^i / k_tooth (the share of the load the pair carries through its tooth
springs); in single contact this is exactly the traditional formula; (2)
eq 11 is split among the pairs in proportion to k_tooth^i, k_i = k_n k_tooth^i /
k_tooth, so sum_i k_i equals eq 11 exactly; (3) lambda_p = lambda_g = 1 by
default (keyword ``foundation_lambda``): the value of Ma et al.'s correction
coefficient could not be checked against the original here, lambda = 1 is the
"fully shared" foundation limit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Optional, Tuple

import numpy as np

from .hertz import hertz_stiffness_N_per_m
from .foundation import sainsot_compliance_m_per_N
from .gearpair import GearPairSpec, GearSpec, MeshModelOptions
from .geometry import PairGeometry, half_tooth_angle_at_base, pair_geometry, transverse_equivalent


class StiffnessError(ValueError):
    """Bad input to the stiffness functions (message names the argument)."""


_GL_N = 48
_GL_X, _GL_W = np.polynomial.legendre.leggauss(_GL_N)

#: Timoshenko shear correction factor of a rectangular section used by the seed papers
SHEAR_FACTOR = 1.2


def cantilever_compliance_m_per_N(x_m, dx_weights_m, half_thickness_m, x_load_m, y_load_m,
                                  alpha1_rad, youngs_modulus_Pa: float, poisson_ratio: float,
                                  width_m: float) -> dict:
    """Bending, shear and axial compliances (m/N) of a cantilever under a unit load.

    Quadrature form of Zhao et al. 2022 eq (15): the beam lies along x (m), its section
    at quadrature node x_k has half thickness h_k (m) and quadrature weight
    dx_k (m); the load (1 N) acts at (x_load, y_load) at angle alpha1 to the
    normal of the beam axis.  Arrays broadcast as (..., n_nodes) for the
    nodes and (...) for the load quantities.  Returns a dict of arrays
    'bending', 'shear', 'axial'.
    """
    E = float(youngs_modulus_Pa)
    G = E / (2.0 * (1.0 + poisson_ratio))
    x = np.asarray(x_m, dtype=float)
    w = np.asarray(dx_weights_m, dtype=float)
    h = np.asarray(half_thickness_m, dtype=float)
    a1 = np.asarray(alpha1_rad, dtype=float)[..., None]
    xl = np.asarray(x_load_m, dtype=float)[..., None]
    yl = np.asarray(y_load_m, dtype=float)[..., None]
    I = (2.0 * h) ** 3 * width_m / 12.0
    A = 2.0 * h * width_m
    ca, sa = np.cos(a1), np.sin(a1)
    bending = np.sum(w * (ca * (xl - x) - yl * sa) ** 2 / (E * I), axis=-1)
    shear = np.sum(w * SHEAR_FACTOR * ca ** 2 / (G * A), axis=-1)
    axial = np.sum(w * sa ** 2 / (E * A), axis=-1)
    return {"bending": bending, "shear": shear, "axial": axial}


def root_half_angle_rad(gear: GearSpec, geom: PairGeometry, which: int) -> float:
    """Sainsot theta_f (rad) of gear ``which`` from the rack-generated root (see module doc)."""
    gv = geom.gear_values(which)
    m, a = geom.module_m, geom.alpha_rad
    z, x, r = gv["z"], gv["x"], gv["r"]
    c = gear.tip_clearance_coefficient
    ha = gear.addendum_coefficient
    rho_t = c * m / (1.0 - math.sin(a))
    u_t = (math.pi * m / 4.0 - x * m * math.tan(a)) - (ha + c - x) * m * math.tan(a) \
        - rho_t * math.tan(math.pi / 4.0 - a / 2.0)
    u_t = max(u_t, 0.0)
    return math.pi / z - u_t / r


def hub_radius_m(gear: GearSpec, geom: PairGeometry, which: int) -> float:
    """r_int (m): ``gear.hub_radius_m`` or, when None, r_f/2 (documented choice)."""
    rf = geom.gear_values(which)["rf"]
    return gear.hub_radius_m if gear.hub_radius_m is not None else 0.5 * rf


def tooth_compliance_m_per_N(gear: GearSpec, geom: PairGeometry, which: int, s_m,
                             width_m: float) -> dict:
    """Compliances (m/N) of ONE tooth of gear ``which`` (1 pinion, 2 gear).

    Unit normal load at LOA positions ``s_m`` (m from N1; array), slice width
    ``width_m`` (m).  Returns arrays 'bending', 'shear', 'axial' (Zhao et al. 2022 eq 15)
    and 'foundation' (Sainsot 2004, Zhao et al. 2022 eq 12), plus 'alpha1_rad'.
    NaN entries of ``s_m`` give NaN compliances.
    """
    if which not in (1, 2):
        raise StiffnessError(f"which: must be 1 (pinion) or 2 (gear), got {which!r}")
    if not (isinstance(width_m, (int, float)) and math.isfinite(width_m) and width_m > 0):
        raise StiffnessError(f"width_m: must be a finite positive length, got {width_m!r}")
    s = np.atleast_1d(np.asarray(s_m, dtype=float))
    gv = geom.gear_values(which)
    rb, rf, z, xs = gv["rb"], gv["rf"], gv["z"], gv["x"]
    E = gear.material.youngs_modulus_Pa
    nu = gear.material.poisson_ratio
    a2 = half_tooth_angle_at_base(z, xs, geom.alpha_rad)
    roll = geom.roll_length_at(which, s)
    valid = np.isfinite(roll)
    out = {k: np.full(s.shape, np.nan) for k in ("bending", "shear", "axial", "foundation", "alpha1_rad")}
    if not np.any(valid):
        return out
    ell = roll[valid]
    if np.any(ell < -1e-12 * rb):
        raise StiffnessError("s_m: contact below the base circle of gear %d" % which)
    phi = np.maximum(ell, 0.0) / rb                      # roll angle of the load point
    a1 = phi - a2
    xP = rb * (np.cos(a1) + phi * np.sin(a1))
    yP = rb * (phi * np.cos(a1) - np.sin(a1))

    # involute segment in the roll angle u: rho = rb sqrt(1 + u^2), inv(alpha_rho) = u - atan(u)
    u0 = math.sqrt(max(rf * rf / (rb * rb) - 1.0, 0.0)) if rf > rb else 0.0
    if np.any(phi < u0 - 1e-12):
        raise StiffnessError(f"s_m: contact below the root circle of gear {which}")
    half = 0.5 * (phi - u0)[:, None]
    u = u0 + half * (_GL_X[None, :] + 1.0)
    wq = half * _GL_W[None, :]
    rho = rb * np.sqrt(1.0 + u * u)
    psi = a2 - (u - np.arctan(u))
    x_inv = rho * np.cos(psi)
    h_inv = rho * np.sin(psi)
    drho_du = rb * u / np.sqrt(1.0 + u * u)
    dpsi_du = -u * u / (1.0 + u * u)                     # d/du of -(u - atan u)
    dx_du = drho_du * np.cos(psi) - rho * np.sin(psi) * dpsi_du
    parts = cantilever_compliance_m_per_N(x_inv, wq * dx_du, h_inv, xP, yP, a1, E, nu, width_m)

    if rf < rb:
        hb = rb * math.sin(a2)
        if hb >= rf:
            raise StiffnessError(f"gear {which}: root circle inside the tooth base width (r_f too small)")
        a3 = math.asin(hb / rf)
        x0, x1 = rf * math.cos(a3), rb * math.cos(a2)
        xs_ = 0.5 * (x1 - x0) * (_GL_X + 1.0) + x0
        ws_ = 0.5 * (x1 - x0) * _GL_W
        rect = cantilever_compliance_m_per_N(xs_[None, :], ws_[None, :], np.full((1, _GL_N), hb),
                                             xP, yP, a1, E, nu, width_m)
        for k in parts:
            parts[k] = parts[k] + rect[k]

    theta_f = root_half_angle_rad(gear, geom, which)
    r_int = hub_radius_m(gear, geom, which)
    u_f = rb / np.cos(a1) - rf
    found = sainsot_compliance_m_per_N(u_f, 2.0 * rf * theta_f, theta_f, rf / r_int, a1, E, width_m)
    for k, v in (("bending", parts["bending"]), ("shear", parts["shear"]), ("axial", parts["axial"]),
                 ("foundation", found), ("alpha1_rad", a1)):
        out[k][valid] = v
    return out


@dataclass(frozen=True)
class SlotStiffness:
    """Per-slot tooth-pair mesh stiffness on the pinion-angle grid (SI).

    ``phi_rad`` (n,): phi_j = j * mesh_period / n_per_mesh, phi = 0 when a pair
    enters at A; ``k_N_per_m`` (slots, n): stiffness of the pair that occupies
    each slot (whole face width), 0 outside the contact zone;
    ``s_m`` (slots, n): its LOA contact position (NaN when out of contact);
    ``k_per_slice_N_per_m`` (slots, n): the same per face-width slice.
    """

    phi_rad: np.ndarray
    k_N_per_m: np.ndarray
    s_m: np.ndarray
    k_per_slice_N_per_m: np.ndarray
    slices: int
    slice_width_m: float
    mesh_period_rad: float
    #: helical pairs only (docs/helical.md): (slots, slices, n) LOA position of each slice's
    #: contact point, NaN out of contact; None for spur pairs (every slice at ``s_m``)
    s_slice_m: Optional[np.ndarray] = None
    #: helical pairs only: (slots, slices, n) share of each slice's width in contact (0 ... 1; a
    #: slice crossing the entry or exit line is partly engaged); None for spur pairs
    slice_contact_fraction: Optional[np.ndarray] = None

    @property
    def k_total_N_per_m(self) -> np.ndarray:
        """Total mesh stiffness (n,) in N/m: sum over slots."""
        return self.k_N_per_m.sum(axis=0)


def _pair_components(pair: GearPairSpec, geom: PairGeometry, s: np.ndarray, width_m: float,
                     contact_factor: float = 1.0):
    """Per-pair tooth stiffness k_tooth^i and foundation compliances at positions s (1-D).

    ``contact_factor`` scales the contact stiffness (helical slices: cos(beta_b), docs/helical.md).
    """
    cp = tooth_compliance_m_per_N(pair.pinion, geom, 1, s, width_m)
    cg = tooth_compliance_m_per_N(pair.gear, geom, 2, s, width_m)
    kh = hertz_stiffness_N_per_m(pair, width_m)
    if contact_factor != 1.0:
        kh = kh * contact_factor
    c_teeth = (cp["bending"] + cp["shear"] + cp["axial"] + cg["bending"] + cg["shear"] + cg["axial"])
    k_tooth = 1.0 / (1.0 / kh + c_teeth)
    return k_tooth, cp["foundation"], cg["foundation"]


def combine_pairs(k_tooth: np.ndarray, cf_p: np.ndarray, cf_g: np.ndarray, opts: MeshModelOptions,
                  foundation_lambda: Tuple[float, float] = (1.0, 1.0)) -> np.ndarray:
    """Per-pair mesh stiffness (N/m) from per-pair tooth stiffness and foundation compliances.

    Arrays are (pairs, n); entries with k_tooth = 0 (or NaN) are out of contact.
    Implements Zhao et al. 2022 eq (11) with the split described in the module doc,
    or the traditional independent-pair sum when the correction is off.
    """
    kt = np.where(np.isfinite(k_tooth), k_tooth, 0.0)
    if not opts.foundation:
        return kt.copy()
    lp, lg = foundation_lambda
    cf = np.where(kt > 0, np.nan_to_num(cf_p) / lp + np.nan_to_num(cf_g) / lg, 0.0)
    if not opts.shared_foundation_correction:
        with np.errstate(divide="ignore"):
            return np.where(kt > 0, 1.0 / (1.0 / np.where(kt > 0, kt, 1.0) + cf), 0.0)
    K = kt.sum(axis=0)
    safe_K = np.where(K > 0, K, 1.0)
    cf_mean = (kt * cf).sum(axis=0) / safe_K
    k_n = np.where(K > 0, 1.0 / (cf_mean + 1.0 / safe_K), 0.0)
    return kt * (k_n / safe_K)[None, :]


def _slot_grid(slots, need: int, need_text: str, n_per_mesh, opts: MeshModelOptions, foundation_lambda):
    """The checked (slots, slices) of a slot-stiffness computation: ``slots`` None is ``need``
    (:func:`required_slots`, ``need_text`` says where it comes from), otherwise an integer >=
    ``need``; ``n_per_mesh`` an integer >= 2, ``opts.slices`` >= 1, both foundation factors > 0."""
    if slots is None:
        slots = need
    if isinstance(slots, bool) or not isinstance(slots, (int, np.integer)) or slots < need:
        raise StiffnessError(f"slots: must be an integer >= {need_text}, got {slots!r}")
    if isinstance(n_per_mesh, bool) or not isinstance(n_per_mesh, (int, np.integer)) or n_per_mesh < 2:
        raise StiffnessError(f"n_per_mesh: must be an integer >= 2, got {n_per_mesh!r}")
    n_slices = int(opts.slices)
    if n_slices < 1:
        raise StiffnessError(f"opts.slices: must be >= 1, got {opts.slices!r}")
    for lam in foundation_lambda:
        if not (lam > 0):
            raise StiffnessError(f"foundation_lambda: must be > 0, got {foundation_lambda!r}")
    return slots, n_slices


def slot_stiffness(pair: GearPairSpec, geom: Optional[PairGeometry] = None,
                   opts: Optional[MeshModelOptions] = None, slots: Optional[int] = None,
                   n_per_mesh: int = 128, *,
                   foundation_lambda: Tuple[float, float] = (1.0, 1.0)) -> SlotStiffness:
    """Per-slot TVMS of a perfect spur pair (see :class:`SlotStiffness`).

    ``slots`` defaults to ceil(contact ratio) and must be at least that
    (one pair per slot at any time).  The pair starting mesh n lives in slot
    n % slots; its contact point is s = s_A + r_b1 (phi - n * mesh_period).
    Slices of a perfect spur pair are identical, so one slice is computed and
    scaled (every stiffness term is proportional to the slice width).
    """
    geom = pair_geometry(pair) if geom is None else geom
    opts = MeshModelOptions() if opts is None else opts
    if geom.helix_angle_rad != 0.0:
        return helical_slot_stiffness(pair, geom, opts, slots, n_per_mesh,
                                      foundation_lambda=foundation_lambda)
    eps = geom.contact_ratio
    min_slots = required_slots(geom)
    slots, n_slices = _slot_grid(slots, min_slots, f"ceil(contact ratio) = {min_slots}", n_per_mesh, opts,
                                 foundation_lambda)
    b = min(pair.pinion.face_width_m, pair.gear.face_width_m)
    w = b / n_slices
    mp = geom.mesh_period_rad
    n = slots * n_per_mesh
    j = np.arange(n)
    phi = j * (mp / n_per_mesh)
    # time since slot i's current pair entered, in mesh periods (integer arithmetic on the grid)
    tau = ((j[None, :] - np.arange(slots)[:, None] * n_per_mesh) % n) / n_per_mesh
    in_contact = tau <= eps * (1.0 + 1e-12)
    s = np.where(in_contact, geom.s_start_m + tau * geom.base_pitch_m, np.nan)
    s = np.minimum(s, geom.s_end_m)
    kt = np.zeros_like(s)
    cfp = np.zeros_like(s)
    cfg = np.zeros_like(s)
    flat = s[in_contact]
    k1, f1, f2 = _pair_components(pair, geom, flat, w)
    kt[in_contact], cfp[in_contact], cfg[in_contact] = k1, f1, f2
    k_slice = combine_pairs(kt, cfp, cfg, opts, foundation_lambda)
    return SlotStiffness(phi_rad=phi, k_N_per_m=k_slice * n_slices, s_m=s,
                         k_per_slice_N_per_m=k_slice, slices=n_slices, slice_width_m=w,
                         mesh_period_rad=mp)


def required_slots(geom: PairGeometry) -> int:
    """Minimum slot count P of a pair (docs/helical.md).

    Spur: ceil(eps_alpha) (at least 1).  Helical: ceil(eps_gamma), plus one
    when eps_gamma is an integer (to 1e-9), so that the pair leaving a slot
    and the one entering it never need the slot at the same grid angle.
    """
    if geom.helix_angle_rad == 0.0:
        return max(1, int(math.ceil(geom.contact_ratio - 1e-12)))
    eg = geom.total_contact_ratio
    p = max(1, int(math.ceil(eg - 1e-12)))
    if abs(eg - round(eg)) < 1e-9:
        p = int(round(eg)) + 1
    return p


def slice_lag_mesh_periods(geom: PairGeometry, slices: int) -> np.ndarray:
    """Lag (in mesh periods) of each face-width slice of a helical pair (docs/helical.md).

    The face is cut into ``slices`` equal slices; slice n's centre lies at
    y_n = (n + 1/2) b/slices from the face end that enters mesh first.  Its
    transverse section meets the line of action y_n tan(beta_b) behind that
    face end (the contact line is inclined at the base helix angle on the plane
    of action), i.e. y_n tan(beta_b)/p_bt mesh periods later.  Spur: all zero.
    """
    n = int(slices)
    y = (np.arange(n) + 0.5) * (geom.face_width_m / n)
    return y * math.tan(geom.base_helix_angle_rad) / geom.base_pitch_m


def engaged_slice_part(geom: PairGeometry, slices: int, tau_n):
    """(share of the width in contact, its middle) of helical slices whose centres are
    ``tau_n`` mesh periods past the entry line (array): slice n spans the lags
    lag_n +- d/2, d = (b/slices) tan(beta_b)/p_bt, and is in contact where
    0 <= tau - lag <= eps_alpha, so the engaged part is
    [max(tau_n - d/2, 0), min(tau_n + d/2, eps_alpha)] (docs/helical.md, "Slice sawtooth")."""
    d = (geom.face_width_m / int(slices)) * math.tan(geom.base_helix_angle_rad) / geom.base_pitch_m
    t = np.asarray(tau_n, dtype=float)
    lo = np.maximum(t - 0.5 * d, 0.0)
    hi = np.minimum(t + 0.5 * d, geom.contact_ratio)
    return np.clip((hi - lo) / d, 0.0, 1.0), 0.5 * (lo + hi)


def virtual_normal_section(pair: GearPairSpec, geom: PairGeometry) -> Tuple[GearPairSpec, PairGeometry]:
    """Virtual spur pair of the NORMAL section of a helical pair (ISO 6336-1 method B, ISO 21771).

    Virtual tooth numbers z_n = z/(cos^2(beta_b) cos(beta)) (ISO 6336-1), normal
    module m_n, normal pressure angle alpha_n, normal shift x_n, the real
    gears' addendum heights (r_a - r) and dedendum (h_a* + c* - x_n) m_n;
    hub radius scaled so that Sainsot's h_f = r_f/r_int is the real gear's.
    Only the per-gear quantities the tooth compliance needs are meaningful
    (radii, z, x, m_n, alpha_n); the line-of-action fields are set so that
    ``roll_length_at(1, s) = s`` and ``roll_length_at(2, s) = L - s`` with L the
    virtual pair's N1N2 at its reference centre distance.
    """
    cbb, cb = math.cos(geom.base_helix_angle_rad), math.cos(geom.helix_angle_rad)
    mn, an = geom.normal_module_m, geom.normal_pressure_angle_rad
    vals = {}
    specs = {}
    for which, gs in ((1, pair.pinion), (2, pair.gear)):
        gv = geom.gear_values(which)
        zn = gv["z"] / (cbb * cbb * cb)
        rn = mn * zn / 2.0
        rfn = rn - mn * (gs.addendum_coefficient + gs.tip_clearance_coefficient - gs.profile_shift)
        hf = gv["rf"] / hub_radius_m(gs, geom, which)
        vals[which] = dict(z=zn, x=gs.profile_shift, r=rn, rb=rn * math.cos(an),
                           ra=rn + (gv["ra"] - gv["r"]), rf=rfn)
        specs[which] = replace(gs, hub_radius_m=rfn / hf, helix_angle_rad=0.0)
    v1, v2 = vals[1], vals[2]
    L = (v1["r"] + v2["r"]) * math.sin(an)
    vgeom = replace(geom, z1=v1["z"], z2=v2["z"], module_m=mn, alpha_rad=an, x1=v1["x"], x2=v2["x"],
                    r1_m=v1["r"], r2_m=v2["r"], rb1_m=v1["rb"], rb2_m=v2["rb"], ra1_m=v1["ra"],
                    ra2_m=v2["ra"], rf1_m=v1["rf"], rf2_m=v2["rf"], rw1_m=v1["r"], rw2_m=v2["r"],
                    alpha_w_rad=an, center_distance_m=v1["r"] + v2["r"],
                    reference_center_distance_m=v1["r"] + v2["r"], base_pitch_m=math.pi * mn * math.cos(an),
                    loa_length_m=L, helix_angle_rad=0.0, base_helix_angle_rad=0.0, overlap_ratio=0.0)
    return replace(pair, pinion=specs[1], gear=specs[2]), vgeom


def _normal_roll_m(geom: PairGeometry, vgeom: PairGeometry, which: int, s_m: np.ndarray) -> np.ndarray:
    """Roll length on the virtual normal-section gear of the point at the same height above the
    reference circle as the transverse contact point at LOA position s (m)."""
    gv, vv = geom.gear_values(which), vgeom.gear_values(which)
    rho = np.sqrt(gv["rb"] ** 2 + geom.roll_length_at(which, s_m) ** 2)
    rho_v = vv["r"] + (rho - gv["r"])
    return np.sqrt(np.maximum(rho_v * rho_v - vv["rb"] ** 2, 0.0))


def helical_slice_compliances(pair: GearPairSpec, geom: PairGeometry, s_m: np.ndarray, width_m: float):
    """(c_teeth, c_foundation_pinion, c_foundation_gear), m/N, of helical slices of face width
    ``width_m`` at transverse LOA positions ``s_m`` (m from N1, finite), on the normal section:
    the virtual spur gear of :func:`virtual_normal_section` at the point of the same height
    above the reference circle, strip length w / cos(beta_b) (the slice's piece of the inclined
    contact line); c_teeth = bending + shear + axial of both teeth (Zhao et al. 2022 eq 14-15), the
    foundation compliances of each gear (Sainsot, eq 12).  Along the normal line of action;
    :func:`helical_slot_stiffness` turns them to the transverse one."""
    vpair, vgeom = virtual_normal_section(pair, geom)
    wn = width_m / math.cos(geom.base_helix_angle_rad)   # contact-line length of the slice
    u1 = _normal_roll_m(geom, vgeom, 1, s_m)
    u2 = _normal_roll_m(geom, vgeom, 2, s_m)
    cp = tooth_compliance_m_per_N(vpair.pinion, vgeom, 1, u1, wn)
    cg = tooth_compliance_m_per_N(vpair.gear, vgeom, 2, vgeom.loa_length_m - u2, wn)
    c_teeth = (cp["bending"] + cp["shear"] + cp["axial"] + cg["bending"] + cg["shear"] + cg["axial"])
    return c_teeth, cp["foundation"], cg["foundation"]


def _helical_slice_components(pair: GearPairSpec, geom: PairGeometry, s_m: np.ndarray, width_m: float):
    """(k_tooth, foundation compliance pinion, gear) of helical slices at transverse LOA positions s,
    along the transverse line of action (see :func:`helical_slot_stiffness`)."""
    cbb = math.cos(geom.base_helix_angle_rad)
    wn = width_m / cbb                                   # contact-line length of the slice
    c_teeth, cf_p, cf_g = helical_slice_compliances(pair, geom, s_m, width_m)
    kh = hertz_stiffness_N_per_m(pair, wn)
    k_tooth_n = 1.0 / (1.0 / kh + c_teeth)
    t = cbb * cbb                                        # normal -> transverse: k_t = k_n cos^2(beta_b)
    return k_tooth_n * t, cf_p / t, cf_g / t


def helical_slot_stiffness(pair: GearPairSpec, geom: PairGeometry, opts: MeshModelOptions,
                           slots: Optional[int] = None, n_per_mesh: int = 128, *,
                           foundation_lambda: Tuple[float, float] = (1.0, 1.0),
                           section: str = "normal", partial_slices: bool = True) -> SlotStiffness:
    """Per-slot TVMS of a perfect helical pair by staggered face-width slices (docs/helical.md).

    Each of the ``opts.slices`` slices (width w = b/slices) is a thin spur gear
    in the transverse plane (the pair's transverse section,
    :func:`gearfmu.gear.geometry.transverse_equivalent`) whose contact point is
    s_n = s_A + p_bt (tau - lag_n), tau the mesh periods since the pair's leading
    face end passed A, lag_n from :func:`slice_lag_mesh_periods`; it is in
    contact for 0 <= tau - lag_n <= eps_alpha.  Its stiffness along the transverse
    line of action is the spur slice stiffness of the transverse tooth (bending,
    shear, axial compression, Sainsot foundation: the transverse component of the
    normal load is the transverse force) in series with the contact stiffness
    times cos(beta_b) (CHOICE, docs/helical.md: the contact line of a slice is
    w/cos(beta_b) long, the normal load F_t/cos(beta_b), the normal approach
    delta_t cos(beta_b), so k_h,t = k_h(w/cos beta_b) cos^2 beta_b = k_h(w) cos beta_b).
    Slices are independent springs in parallel (no coupling through the tooth,
    the usual slicing assumption); the pair's stiffness is the sum over its
    slices in contact.  The foundation options act per slice across the pairs.
    Slot rule: :func:`required_slots`.  Stiffness is along the transverse line
    of action, so the dynamic model (x = theta1 rb1 - theta2 rb2) is unchanged.

    Partial slices (``partial_slices``, default): slice n spans the lags
    lag_n +- d/2, d = w tan(beta_b)/p_bt, so while the entry line (tau - lag = 0) or the
    exit line (tau - lag = eps_alpha) crosses it, only the share f of its width between
    them is in contact.  That share is a strip of width f w at the middle of its engaged
    part; every component of the slice (Hertz, tooth and foundation terms) is
    proportional to the strip width, so the slice gets k_tooth f and compliances / f.
    The engaged face width of a pair is then exactly that of the continuous face (the
    contact-line length of a helical pair), and the all-or-nothing steps of whole slices
    entering and leaving (a sawtooth of about 1/(NS eps_alpha) of the mean stiffness,
    docs/helical.md) are gone.  ``partial_slices=False`` keeps the all-or-nothing rule
    for comparison.
    """
    need = required_slots(geom)
    slots, NS = _slot_grid(slots, need, f"{need} (from the total contact ratio {geom.total_contact_ratio:.6g})",
                           n_per_mesh, opts, foundation_lambda)
    if section not in ("normal", "transverse"):
        raise StiffnessError(f"section: must be 'normal' or 'transverse', got {section!r}")
    eps = geom.contact_ratio
    w = geom.face_width_m / NS
    mp = geom.mesh_period_rad
    n = slots * n_per_mesh
    j = np.arange(n)
    phi = j * (mp / n_per_mesh)
    tau = ((j[None, :] - np.arange(slots)[:, None] * n_per_mesh) % n) / n_per_mesh      # (P, n)
    tau_n = tau[:, None, :] - slice_lag_mesh_periods(geom, NS)[None, :, None]           # (P, NS, n)
    if partial_slices:  # engaged share of each slice's lag span [tau_n - d/2, tau_n + d/2]
        frac, tau_mid = engaged_slice_part(geom, NS, tau_n)
        in_contact = frac > 1e-12
        tau_n = np.where(in_contact, tau_mid, tau_n)
    else:
        in_contact = (tau_n >= 0.0) & (tau_n <= eps * (1.0 + 1e-12))
        frac = in_contact.astype(float)
    s = np.where(in_contact, geom.s_start_m + tau_n * geom.base_pitch_m, np.nan)
    s = np.minimum(s, geom.s_end_m)
    kt = np.zeros_like(s)
    cfp = np.zeros_like(s)
    cfg = np.zeros_like(s)
    if np.any(in_contact):
        if section == "normal":
            k1, f1, f2 = _helical_slice_components(pair, geom, s[in_contact], w)
        else:
            k1, f1, f2 = _pair_components(transverse_equivalent(pair), geom, s[in_contact], w,
                                          contact_factor=math.cos(geom.base_helix_angle_rad))
        f = frac[in_contact]  # strip width f w: stiffness x f, compliances / f
        kt[in_contact], cfp[in_contact], cfg[in_contact] = k1 * f, f1 / f, f2 / f
    shape = (slots, NS * n)
    k_slice = combine_pairs(kt.reshape(shape), cfp.reshape(shape), cfg.reshape(shape), opts,
                            foundation_lambda).reshape(slots, NS, n)
    k_pair = k_slice.sum(axis=1)
    cnt = in_contact.sum(axis=1)
    s_sum = np.where(in_contact, s, 0.0).sum(axis=1)
    s_mean = np.where(cnt > 0, s_sum / np.maximum(cnt, 1), np.nan)   # mean over slices in contact
    return SlotStiffness(phi_rad=phi, k_N_per_m=k_pair, s_m=s_mean, k_per_slice_N_per_m=k_slice,
                         slices=NS, slice_width_m=w, mesh_period_rad=mp, s_slice_m=s,
                         slice_contact_fraction=np.where(in_contact, frac, 0.0))


def pair_stiffness_at_N_per_m(pair: GearPairSpec, geom: PairGeometry, s_m, width_m: Optional[float] = None,
                              foundation: bool = True) -> np.ndarray:
    """Stiffness (N/m) of ONE tooth pair in single contact at LOA positions s (traditional series).

    k = 1/(1/k_h + 1/k_tp + 1/k_tg + 1/k_fp + 1/k_fg) over ``width_m``
    (default the face width).
    """
    b = min(pair.pinion.face_width_m, pair.gear.face_width_m) if width_m is None else width_m
    kt, f1, f2 = _pair_components(pair, geom, np.atleast_1d(np.asarray(s_m, float)), b)
    if foundation:
        return 1.0 / (1.0 / kt + f1 + f2)
    return kt


def mean_mesh_stiffness_N_per_m(pair: GearPairSpec, geom: Optional[PairGeometry] = None,
                                opts: Optional[MeshModelOptions] = None, n_per_mesh: int = 256,
                                **kw) -> float:
    """Mean total mesh stiffness (N/m, whole face width) over one mesh period."""
    st = slot_stiffness(pair, geom, opts, None, n_per_mesh, **kw)
    return float(st.k_total_N_per_m.mean())
