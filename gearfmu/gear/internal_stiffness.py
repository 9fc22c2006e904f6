"""Tooth-pair stiffness of the planet-ring (internal) mesh, with the ring rim's compliance (SI units).

The potential-energy method of the external pair (:mod:`gearfmu.gear.stiffness`, Zhao et al. 2022 eq 15:
bending, shear and axial compression of each tooth as a cantilever of variable section, in series
with the Hertz contact stiffness) applied to the internal tooth, with the ring's rim as a curved
beam between its supports -- the model of Z. Chen, Y. Shao, *Mesh stiffness of an internal spur
gear pair with ring gear rim deformation*, Mech. Mach. Theory 69 (2013) 1-12.  Their paper could
not be read here; the formulation below is written from the method it names (potential energy
of the internal tooth, rim deformation of a ring held at discrete supports) and states every
choice.

Ring tooth (a cantilever fixed at the root circle rf2, pointing inwards to the tip ra2):

* the flank is the internal involute of :func:`gearfmu.gear.internal.ring_half_tooth_angle_rad`,
  F(u) = rho(u) (cos psi(u), sin psi(u)), rho = rb2 sqrt(1 + u^2), psi = psi0 + u - atan(u), from
  the tip to the root circle (CHOICE: the involute runs to the root circle; the small fillet of a
  shaper-cut ring is not modelled);
* the beam axis xi runs along the tooth centre line from the root section (xi = 0 at
  X_root = rf2 cos psi(rf2)) towards the gear axis, xi = X_root - rho cos psi; the half thickness
  is h = rho sin psi;
* the unit load acts at the contact point P along the flank normal pointing into the tooth (for
  an involute: along the line of action); with f_xi, f_eta its components along and across the
  axis, the compliances are the integrals of Zhao et al. 2022 eq 15 written for any axis orientation
      1/k_b = int [f_eta (xi_P - xi) - eta_P f_xi]^2/(E I) dxi,  1/k_s = int 1.2 f_eta^2/(G A) dxi,
      1/k_a = int f_xi^2/(E A) dxi,   I = (2h)^3 w/12, A = 2 h w,
  by Gauss-Legendre quadrature in the roll parameter u (gearfmu.gear.stiffness.cantilever_compliance_m_per_N).
  The same construction applied to an external tooth gives the external compliances of
  gearfmu.gear.stiffness (tests/unit/gear/test_internal_gear.py checks it).

Rim (CHOICE, after Chen & Shao's ring held at discrete supports): the rim below the tooth roots
is a thin circular curved beam of centroid radius R = rf2 + t/2, section t x b (rim thickness t,
face width b), clamped at N_s equally spaced supports (pins, bolts or splines against the
housing).  One span, 0 <= phi <= Phi = 2 pi/N_s, clamped at both ends, carries the tooth load
transferred to the rim centroid under the loaded tooth at angle beta: the force d (unit, along the
line of action) and the moment ((P - C_beta) x d) of its lever arm.  By the unit-load method
(Castigliano) on the arc cut free at phi = Phi with the three redundant end forces,
    f_ij = int_0^min(a_i, a_j) [M_i M_j/(E I) + N_i N_j/(E A) + 1.2 V_i V_j/(G A)] R dphi,
    G = f_BB - f_BX f_XX^-1 f_XB       (3 x 3 flexibility of the point beta, global x, y and rotation),
and the rim compliance along the line of action is c_rim(beta) = v^T G v with v = (d_x, d_y, lever arm
moment).  Thin curved beam (no Winkler correction; CHOICE, t << R).  The mesh moves around the ring
with the carrier, so c_rim varies with the carrier angle; the tables hold the mean over one span
(CHOICE: mesh-period tables cannot carry the slower support-passing modulation; its range is
reported by :func:`rim_compliance_m_per_N`).  The rim is shared by the tooth pairs in contact (their
teeth sit side by side on one span): it acts on the total mesh force, k_mesh = 1/(1/sum_i k_i' + c_rim)
with c_rim at the load-weighted mean position (weights k_i'/sum k_i'), and is split among the pairs in
proportion to k_i' (the rule of gearfmu.gear.stiffness.combine_pairs for the shared foundation).

Planet tooth: the external tooth of gearfmu.gear.stiffness with its Sainsot fillet-foundation
compliance.  Ring tooth root (CHOICE): the local fillet-foundation compliance of the ring tooth is
Sainsot's formula (gearfmu.gear.foundation) with the ring tooth's root half angle theta_f =
psi2(rf2) (the involute half angle at the root circle), S_f = 2 rf2 theta_f, the load arm u_f =
rf2 - rb2/|cos(alpha_m)| (from the root circle inwards to where the load line crosses the centre
line; alpha_m the angle between the load and the normal to the centre line) and h_f = 2, the value
this project takes for an external gear without a given bore.  Sainsot et al. fitted the formula
to external gear bodies; here it stands for the local deformation of the ring body at the tooth
root, while the curved beam above carries the rim's bending between its supports.  Without this
term the internal mesh comes out about 50 % stiffer than ISO 6336-1 method B for internal gears
(z_n2 = infinity), with it within the +-25 % band of the external pairs (tests/unit/gear/test_internal_gear.py).
The two foundations combine per pair as the external pair's do (gearfmu.gear.stiffness.combine_pairs,
``opts.foundation`` and ``opts.shared_foundation_correction``).  Contact: the Yang & Sun Hertz
stiffness (gearfmu.gear.hertz; it does not depend on the curvature, so the concave ring flank
changes nothing there).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from .foundation import sainsot_compliance_m_per_N
from .gearpair import GearPairSpec, GearSpec, MeshModelOptions
from .hertz import hertz_stiffness_N_per_m
from .internal import InternalPairGeometry, RingRim, internal_pair_geometry, ring_half_tooth_angle_rad
from .stiffness import (SlotStiffness, StiffnessError, cantilever_compliance_m_per_N, combine_pairs,
                        tooth_compliance_m_per_N)

__all__ = ["ring_tooth_compliance_m_per_N", "flank_tooth_compliance_m_per_N", "curved_beam_flexibility",
           "rim_compliance_m_per_N", "RimCompliance", "internal_slot_stiffness", "mean_internal_mesh_stiffness_N_per_m"]

_GL_N = 48
_GL_X, _GL_W = np.polynomial.legendre.leggauss(_GL_N)
#: span positions averaged for the mean rim compliance (midpoints of equal parts)
RIM_POSITIONS = 16
#: Sainsot's h_f = r_f/r_int taken for the ring tooth's root (module docstring)
RING_FOUNDATION_HF = 2.0


def flank_tooth_compliance_m_per_N(rb_m: float, psi_of_u, dpsi_du, u_root: float, u_load, internal: bool,
                                   youngs_modulus_Pa: float, poisson_ratio: float, width_m: float) -> dict:
    """Bending, shear and axial compliances (m/N) of one involute tooth under a unit normal load
    (module docstring): the flank F(u) = rho(u)(cos psi(u), sin psi(u)), rho = rb sqrt(1 + u^2),
    from the root section at roll parameter ``u_root`` to the load at ``u_load`` (array);
    ``internal``: the tooth points inwards (root outside).  Returns arrays 'bending', 'shear',
    'axial' and the load angle 'alpha1_rad' = atan2(f_xi, f_eta)."""
    uP = np.atleast_1d(np.asarray(u_load, dtype=float))
    half = 0.5 * (uP - u_root)[:, None]
    u = u_root + half * (_GL_X[None, :] + 1.0)
    wq = half * _GL_W[None, :]                         # signed: du from the root towards the load
    rho = rb_m * np.sqrt(1.0 + u * u)
    psi = psi_of_u(u)
    X = rho * np.cos(psi)
    drho = rb_m * u / np.sqrt(1.0 + u * u)
    dX = drho * np.cos(psi) - rho * np.sin(psi) * dpsi_du(u)
    sgn = -1.0 if internal else 1.0                    # xi along the axis from the root to the tip
    rho_f = rb_m * math.sqrt(1.0 + u_root * u_root)
    X_root = rho_f * math.cos(float(psi_of_u(np.array(u_root))))
    xi = sgn * (X - X_root)
    dxi = np.abs(sgn * dX * wq)
    rP = rb_m * np.sqrt(1.0 + uP * uP)
    psiP = psi_of_u(uP)
    xiP = sgn * (rP * np.cos(psiP) - X_root)
    etaP = rP * np.sin(psiP)
    # unit normal at P into the tooth: the flank tangent turned by 90 deg towards -e_theta
    drP = rb_m * uP / np.sqrt(1.0 + uP * uP)
    tx = drP * np.cos(psiP) - rP * np.sin(psiP) * dpsi_du(uP)
    ty = drP * np.sin(psiP) + rP * np.cos(psiP) * dpsi_du(uP)
    nx, ny = ty, -tx
    flip = nx * np.sin(psiP) - ny * np.cos(psiP) < 0.0
    nx, ny = np.where(flip, -nx, nx), np.where(flip, -ny, ny)
    nn = np.hypot(nx, ny)
    f_xi, f_eta = sgn * nx / nn, ny / nn
    a1 = np.arctan2(f_xi, f_eta)
    out = cantilever_compliance_m_per_N(xi, dxi, rho * np.sin(psi), xiP, etaP, a1, youngs_modulus_Pa, poisson_ratio,
                                        width_m)
    out["alpha1_rad"] = a1
    return out


def _ring_psi(geom: InternalPairGeometry):
    z, x, a = geom.z2, geom.x2, geom.alpha_rad
    c = math.pi / (2.0 * z) + 2.0 * x * math.tan(a) / z - (math.tan(a) - a)
    return (lambda u: c + (u - np.arctan(u))), (lambda u: u * u / (1.0 + u * u))


def ring_tooth_compliance_m_per_N(ring: GearSpec, geom: InternalPairGeometry, s_m, width_m: float) -> dict:
    """Compliances (m/N) of ONE ring tooth at LOA positions ``s_m`` (m from N1; array) for a slice
    of width ``width_m``: 'bending', 'shear', 'axial', 'foundation' (its root, Sainsot, module
    docstring) and 'alpha1_rad'."""
    if not (isinstance(width_m, (int, float)) and math.isfinite(width_m) and width_m > 0):
        raise StiffnessError(f"width_m: must be a finite positive length, got {width_m!r}")
    s = np.atleast_1d(np.asarray(s_m, dtype=float))
    rb = geom.rb2_m
    u_load = geom.roll_length_at(2, s) / rb
    u_root = math.sqrt(geom.rf2_m ** 2 / rb ** 2 - 1.0)
    if np.any(u_load > u_root * (1.0 + 1e-12)):
        raise StiffnessError("s_m: contact beyond the ring's root circle")
    psi, dpsi = _ring_psi(geom)
    E = ring.material.youngs_modulus_Pa
    out = flank_tooth_compliance_m_per_N(rb, psi, dpsi, u_root, u_load, True, E, ring.material.poisson_ratio,
                                         width_m)
    theta_f = float(ring_half_tooth_angle_rad(geom.z2, geom.x2, geom.alpha_rad, geom.rf2_m, rb))
    a_m = np.arctan(np.tan(out["alpha1_rad"]))         # the load's angle to the normal of the centre line
    u_f = np.maximum(geom.rf2_m - rb / np.abs(np.cos(a_m)), 0.0)
    out["foundation"] = sainsot_compliance_m_per_N(u_f, 2.0 * geom.rf2_m * theta_f, theta_f, RING_FOUNDATION_HF,
                                                   a_m, E, width_m)
    return out


# ------------------------------------------------------------------------------- rim
def _resultants(R: float, a: float, phi: np.ndarray):
    """(N, V, M) at sections phi (< a) of unit Fx, Fy, M applied at the arc point at angle a: rows are
    the three loads, columns the sections (module docstring)."""
    Pa = np.array([R * math.cos(a), R * math.sin(a)])
    cx, cy = R * np.cos(phi), R * np.sin(phi)
    tx, ty = -np.sin(phi), np.cos(phi)
    nx, ny = np.cos(phi), np.sin(phi)
    one, zero = np.ones_like(phi), np.zeros_like(phi)
    N = np.stack([tx, ty, zero])
    V = np.stack([nx, ny, zero])
    dx, dy = Pa[0] - cx, Pa[1] - cy
    M = np.stack([-dy, dx, one])                      # (P_a - C) x F for F = e_x, e_y; then the couple
    return N, V, M


def _flex(R, a, b, lo, hi, EI, EA, GA):
    """int_lo^hi of the loads at a (rows) against the loads at b (columns), R dphi (Gauss)."""
    half = 0.5 * (hi - lo)
    phi = lo + half * (_GL_X + 1.0)
    w = half * _GL_W * R
    Na, Va, Ma = _resultants(R, a, phi)
    Nb, Vb, Mb = _resultants(R, b, phi)
    return (Ma * w) @ Mb.T / EI + (Na * w) @ Nb.T / EA + 1.2 * (Va * w) @ Vb.T / GA


def curved_beam_flexibility(radius_m: float, span_rad: float, beta_rad: float, EI: float, EA: float,
                            GA: float) -> np.ndarray:
    """3 x 3 flexibility (m/N, 1/N, rad/(N m) ...) of the point at angle ``beta_rad`` of a circular arc
    of centroid radius ``radius_m`` clamped at 0 and ``span_rad``: displacements (x, y, rotation)
    under unit Fx, Fy, M there (module docstring: unit-load method, three redundants at the far end).
    EI, EA, GA: bending, axial and shear rigidities of the section."""
    R, Phi, b = float(radius_m), float(span_rad), float(beta_rad)
    if not 0.0 < b < Phi:
        raise StiffnessError(f"beta_rad: must lie inside the span (0, {Phi!r}), got {b!r}")
    f_bb = _flex(R, b, b, 0.0, b, EI, EA, GA)
    f_bx = _flex(R, b, Phi, 0.0, b, EI, EA, GA)
    f_xx = _flex(R, Phi, Phi, 0.0, b, EI, EA, GA) + _flex(R, Phi, Phi, b, Phi, EI, EA, GA)
    return f_bb - f_bx @ np.linalg.solve(f_xx, f_bx.T)


@dataclass(frozen=True)
class RimCompliance:
    """Rim compliance along the line of action (m/N) at LOA positions s: the mean over one span
    (used in the tables) and its smallest and largest value over the span positions."""

    mean_m_per_N: np.ndarray
    min_m_per_N: np.ndarray
    max_m_per_N: np.ndarray


def rim_compliance_m_per_N(ring: GearSpec, rim: RingRim, geom: InternalPairGeometry, s_m,
                           width_m: Optional[float] = None, positions: int = RIM_POSITIONS) -> RimCompliance:
    """Compliance of the ring rim (module docstring) for a unit mesh force at LOA positions ``s_m``
    over the face width ``width_m`` (default the common face width).  A rigid rim
    (``rim.thickness_m`` None) gives zeros."""
    s = np.atleast_1d(np.asarray(s_m, dtype=float))
    if rim.thickness_m is None:
        z = np.zeros_like(s)
        return RimCompliance(z, z, z)
    t = float(rim.thickness_m)
    if not (math.isfinite(t) and t > 0):
        raise StiffnessError(f"rim.thickness_m: must be a finite positive length, got {rim.thickness_m!r}")
    if isinstance(rim.supports, bool) or int(rim.supports) != rim.supports or rim.supports < 2:
        raise StiffnessError(f"rim.supports: must be an integer >= 2, got {rim.supports!r}")
    b = geom.face_width_m if width_m is None else float(width_m)
    E, nu = ring.material.youngs_modulus_Pa, ring.material.poisson_ratio
    R = geom.rf2_m + 0.5 * t
    A = b * t
    EI, EA, GA = E * b * t ** 3 / 12.0, E * A, E / (2.0 * (1.0 + nu)) * A
    Phi = 2.0 * math.pi / int(rim.supports)
    # contact point and force direction in the frame of the loaded tooth (centre line along +x)
    rb = geom.rb2_m
    u = geom.roll_length_at(2, s) / rb
    psi, dpsi = _ring_psi(geom)
    rho, ps = rb * np.sqrt(1.0 + u * u), psi(u)
    Px, Py = rho * np.cos(ps), rho * np.sin(ps)
    dr = rb * u / np.sqrt(1.0 + u * u)
    tx = dr * np.cos(ps) - rho * np.sin(ps) * dpsi(u)
    ty = dr * np.sin(ps) + rho * np.cos(ps) * dpsi(u)
    nx, ny = ty, -tx
    flip = nx * np.sin(ps) - ny * np.cos(ps) < 0.0
    nx, ny = np.where(flip, -nx, nx), np.where(flip, -ny, ny)
    nn = np.hypot(nx, ny)
    dx, dy = nx / nn, ny / nn
    mom = (Px - R) * dy - Py * dx                      # lever arm about the rim centroid under the tooth
    vals = []
    for k in range(int(positions)):
        beta = (k + 0.5) * Phi / int(positions)
        G = curved_beam_flexibility(R, Phi, beta, EI, EA, GA)
        c, sn = math.cos(beta), math.sin(beta)
        # rotate the tooth-frame load into the global frame (the tooth centre line at angle beta)
        gx, gy = c * dx - sn * dy, sn * dx + c * dy
        v = np.stack([gx, gy, mom])
        vals.append(np.einsum("in,ij,jn->n", v, G, v))
    vals = np.array(vals)
    return RimCompliance(vals.mean(axis=0), vals.min(axis=0), vals.max(axis=0))


# ------------------------------------------------------------------------ mesh stiffness
def _pair_components(planet: GearSpec, ring: GearSpec, rim: RingRim, geom: InternalPairGeometry, s: np.ndarray,
                     width_m: float):
    """(k_tooth, planet and ring foundation compliances, rim compliance) of tooth pairs at LOA positions s."""
    cp = tooth_compliance_m_per_N(planet, geom, 1, s, width_m)
    cr = ring_tooth_compliance_m_per_N(ring, geom, s, width_m)
    kh = hertz_stiffness_N_per_m(GearPairSpec(planet, ring), width_m)
    c_teeth = cp["bending"] + cp["shear"] + cp["axial"] + cr["bending"] + cr["shear"] + cr["axial"]
    c_rim = rim_compliance_m_per_N(ring, rim, geom, s, width_m).mean_m_per_N
    return 1.0 / (1.0 / kh + c_teeth), cp["foundation"], cr["foundation"], c_rim


def internal_slot_stiffness(planet: GearSpec, ring: GearSpec, rim: RingRim = RingRim(),
                            geom: Optional[InternalPairGeometry] = None, opts: Optional[MeshModelOptions] = None,
                            slots: Optional[int] = None, n_per_mesh: int = 128) -> SlotStiffness:
    """Per-slot TVMS of a perfect spur planet-ring mesh on the planet-angle grid (see
    :class:`gearfmu.gear.stiffness.SlotStiffness`; slot rules of gearfmu.gear.stiffness.slot_stiffness:
    the pair entering at A at phi = n mesh periods sits in slot n % P, s = s_A + rb1 (phi - n T)).
    Foundations per ``opts`` (gearfmu.gear.stiffness.combine_pairs); the rim shared by the pairs in
    contact (module docstring)."""
    geom = internal_pair_geometry(planet, ring) if geom is None else geom
    opts = MeshModelOptions() if opts is None else opts
    need = max(1, int(math.ceil(geom.contact_ratio - 1e-12)))
    slots = need if slots is None else slots
    if isinstance(slots, bool) or not isinstance(slots, (int, np.integer)) or slots < need:
        raise StiffnessError(f"slots: must be an integer >= ceil(contact ratio) = {need}, got {slots!r}")
    if isinstance(n_per_mesh, bool) or not isinstance(n_per_mesh, (int, np.integer)) or n_per_mesh < 2:
        raise StiffnessError(f"n_per_mesh: must be an integer >= 2, got {n_per_mesh!r}")
    n_slices = int(opts.slices)
    b = geom.face_width_m
    w = b / n_slices
    mp = geom.mesh_period_rad
    n = slots * n_per_mesh
    j = np.arange(n)
    phi = j * (mp / n_per_mesh)
    tau = ((j[None, :] - np.arange(slots)[:, None] * n_per_mesh) % n) / n_per_mesh
    inside = tau <= geom.contact_ratio * (1.0 + 1e-12)
    s = np.where(inside, np.minimum(geom.s_start_m + tau * geom.base_pitch_m, geom.s_end_m), np.nan)
    kt = np.zeros_like(s)
    cfp = np.zeros_like(s)
    cfr = np.zeros_like(s)
    crim = np.zeros_like(s)
    k1, f1, f2, r1 = _pair_components(planet, ring, rim, geom, s[inside], w)
    kt[inside], cfp[inside], cfr[inside], crim[inside] = k1, f1, f2, r1
    k_pair = combine_pairs(kt, cfp, cfr, opts)
    K = k_pair.sum(axis=0)
    safe = np.where(K > 0, K, 1.0)
    c_rim = (k_pair * crim).sum(axis=0) / safe        # at the load-weighted mean position
    k_n = np.where(K > 0, 1.0 / (1.0 / safe + c_rim), 0.0)
    k_slice = k_pair * (k_n / safe)[None, :]
    return SlotStiffness(phi_rad=phi, k_N_per_m=k_slice * n_slices, s_m=s, k_per_slice_N_per_m=k_slice,
                         slices=n_slices, slice_width_m=w, mesh_period_rad=mp)


def mean_internal_mesh_stiffness_N_per_m(planet: GearSpec, ring: GearSpec, rim: RingRim = RingRim(),
                                         geom: Optional[InternalPairGeometry] = None,
                                         opts: Optional[MeshModelOptions] = None, n_per_mesh: int = 256) -> float:
    """Mean total planet-ring mesh stiffness (N/m, whole face width) over one mesh period."""
    st = internal_slot_stiffness(planet, ring, rim, geom, opts, None, n_per_mesh)
    return float(st.k_total_N_per_m.mean())


def ring_stiffness_summary(planet: GearSpec, ring: GearSpec, rim: RingRim,
                           geom: Optional[InternalPairGeometry] = None) -> Tuple[float, float, float]:
    """(mean mesh stiffness with the rim, without it, largest/smallest rim compliance ratio over a
    span at the pitch point) -- for reports (N/m, N/m, 1)."""
    geom = internal_pair_geometry(planet, ring) if geom is None else geom
    with_rim = mean_internal_mesh_stiffness_N_per_m(planet, ring, rim, geom)
    rigid = mean_internal_mesh_stiffness_N_per_m(planet, ring, RingRim(None, rim.supports), geom)
    rc = rim_compliance_m_per_N(ring, rim, geom, [geom.s_pitch_m])
    ratio = float(rc.max_m_per_N[0] / rc.min_m_per_N[0]) if rc.min_m_per_N[0] > 0 else 1.0
    return with_rim, rigid, ratio
