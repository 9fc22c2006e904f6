"""Per-tooth-pair meshing errors (SI units; see docs/physics_errors.md).

Physics implemented here
------------------------
* Profile deviation of one flank, Xu et al. 2022 eq (15):
  ``e_alpha(s) = f_fa/2 sin(2 pi f_r (s - s_o)/(s_f - s_o)) + f_Ha (s - s_o)/(s_f - s_o)``.
* Per-tooth positions from single pitch deviations (ISO 1328-1 cumulative
  pitch deviation, closed over one revolution).
* Per-pair meshing error ``e_pair = e_alpha,pinion + e_alpha,gear + p_pinion + p_gear``.
* Comprehensive (envelope) error of the traditional model (Xu et al. 2022 Fig. 5,
  eq 12).
* Lead crowning per face-width slice, Zhao et al. 2022 eq (16) ``E_pc``.

Sign convention (gearfmu/gear/gearpair.py): a *positive* deviation is a material
deficit along the flank normal; it opens the gap, so a pair is in contact when
the transmission error x exceeds e + b (Xu et al. 2022 eq 6).

Choices (also in docs/physics_errors.md)
----------------------------------------
* Evaluation range of eq (15) = the active profile of that gear, from the
  start of the active profile (root end, ``s_o``) to the tip (``s_f``).
  The roll length ``s`` is measured on that gear's own base circle: for the
  pinion the distance from its tangent point N1 along the line of action, for
  the gear the distance from N2.  Pinion: s_o = s_A (meshing-in point A),
  s_f = s_E = sqrt(ra1^2 - rb1^2).  Gear: u = N1N2 - s,
  u_o = N1N2 - s_E, u_f = N1N2 - s_A = sqrt(ra2^2 - rb2^2).
* Pitch: ``ToothDeviation.pitch_m`` of tooth i is the ISO 1328-1 single pitch
  deviation f_pt,i of the pitch that *ends* at tooth i (between tooth i-1 and
  tooth i), along the line of action, positive = tooth i lags = material
  deficit.  The pitches of one revolution must close, so the mean single pitch
  deviation is removed first (closure enforced); the position error of tooth i
  is the cumulative pitch deviation F_p,i = sum_{k=1..i} (f_pt,k - mean f_pt),
  then shifted to zero mean over the teeth (a common offset of all teeth of one
  gear only shifts the transmission error and carries no dynamics).
* The tooth pair of mesh number n (counted from phi = 0) is pinion tooth
  ``n mod z1`` with gear tooth ``n mod z2``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np

from .gearpair import GearDeviations, GearPairSpec, ToothDeviation
from .stiffness import engaged_slice_part, slice_lag_mesh_periods


class MeshingErrorInputError(ValueError):
    """Bad input to a meshing-error function (names the field and the reason)."""


# --------------------------------------------------------------------------- eq 15
def profile_deviation_m(s_m, dev: ToothDeviation, s_o_m: float, s_f_m: float) -> np.ndarray:
    """Profile deviation e_alpha(s) of one flank (m), Xu et al. 2022 eq (15).

    ``s_m``: involute roll length(s) (m) on this gear's base circle;
    ``s_o_m``/``s_f_m``: start (root end) and end (tip) of the profile
    evaluation range (m).  Values of s outside [s_o, s_f] are clamped to the
    range (the flank is evaluated only where it exists; outside the contact
    zone the value only keeps table interpolation smooth).
    """
    if not (math.isfinite(s_o_m) and math.isfinite(s_f_m)) or not s_f_m > s_o_m:
        raise MeshingErrorInputError(
            f"s_f_m: evaluation range must satisfy s_f > s_o, got s_o={s_o_m!r}, s_f={s_f_m!r}")
    for name in ("profile_form_m", "profile_slope_m", "form_periods"):
        v = getattr(dev, name)
        if not math.isfinite(v):
            raise MeshingErrorInputError(f"{name}: must be finite, got {v!r}")
    if dev.form_periods < 0:
        raise MeshingErrorInputError(f"form_periods: must be >= 0, got {dev.form_periods!r}")
    s = np.asarray(s_m, dtype=float)
    xi = np.clip((s - s_o_m) / (s_f_m - s_o_m), 0.0, 1.0)
    return (0.5 * dev.profile_form_m * np.sin(2.0 * np.pi * dev.form_periods * xi)
            + dev.profile_slope_m * xi)


# --------------------------------------------------------------------------- pitch
def pitch_position_errors_m(deviations: GearDeviations, teeth: int) -> np.ndarray:
    """Position error of every tooth along the line of action (m), shape (teeth,).

    Convention (ISO 1328-1 cumulative pitch deviation, closed over a
    revolution): f_pt,i = ``deviations.tooth(i).pitch_m`` is the deviation of
    the pitch ending at tooth i; the mean is removed so that the pitches close;
    F_p,i = sum_{k=1..i} f'_pt,k; the result is shifted to zero mean.
    Positive = tooth lags = material deficit (opens the gap).
    """
    if int(teeth) != teeth or teeth < 1:
        raise MeshingErrorInputError(f"teeth: must be a positive integer, got {teeth!r}")
    for i, d in deviations.per_tooth:
        if not 0 <= int(i) < teeth:
            raise MeshingErrorInputError(
                f"per_tooth: tooth index {i} out of range 0..{teeth - 1}")
    f = np.array([deviations.tooth(i).pitch_m for i in range(teeth)], dtype=float)
    if not np.all(np.isfinite(f)):
        raise MeshingErrorInputError("pitch_m: must be finite for every tooth")
    f = f - f.mean()
    pos = np.concatenate(([0.0], np.cumsum(f[1:])))
    return pos - pos.mean()


# ------------------------------------------------------------------ pair indices
def tooth_indices(mesh_number, z1: int, z2: int) -> Tuple[np.ndarray, np.ndarray]:
    """(pinion tooth, gear tooth) of the pair in mesh number n: (n mod z1, n mod z2)."""
    n = np.asarray(mesh_number, dtype=np.int64)
    return np.mod(n, z1), np.mod(n, z2)


def table_mesh_count(slots: int, z1: int, z2: int, pinion_teeth_differ: bool,
                     gear_teeth_differ: bool) -> int:
    """Number of mesh periods of the table period.

    P if all teeth are identical; lcm(P, z1) if only pinion teeth differ;
    lcm(P, z2) if only gear teeth differ; lcm(P, z1, z2) if both (the
    hunting-tooth cycle, a multiple of the slot count P).
    """
    for name, v in (("slots", slots), ("teeth_pinion", z1), ("teeth_gear", z2)):
        if int(v) != v or v < 1:
            raise MeshingErrorInputError(f"{name}: must be a positive integer, got {v!r}")
    n = int(slots)
    if pinion_teeth_differ:
        n = math.lcm(n, int(z1))
    if gear_teeth_differ:
        n = math.lcm(n, int(z2))
    return n


def _profile_differs(devs: GearDeviations) -> bool:
    keys = lambda d: (d.profile_form_m, d.profile_slope_m, d.form_periods if d.profile_form_m else 0.0)
    return any(keys(d) != keys(devs.default) for _, d in devs.per_tooth)


def gear_teeth_differ(devs: GearDeviations, teeth: int) -> bool:
    """True when the teeth of one gear give different errors: a profile
    deviation that differs from the default, or pitch positions that are not all
    equal (identical single pitch deviations close to zero positions)."""
    if _profile_differs(devs):
        return True
    return bool(np.any(pitch_position_errors_m(devs, teeth) != 0.0))


def pair_table_mesh_count(pair: GearPairSpec, slots: int) -> int:
    """:func:`table_mesh_count` for a gear pair (hunting-tooth rule)."""
    z1, z2 = pair.pinion.teeth, pair.gear.teeth
    return table_mesh_count(slots, z1, z2, gear_teeth_differ(pair.pinion.deviations, z1),
                            gear_teeth_differ(pair.gear.deviations, z2))


# ------------------------------------------------------------- evaluation ranges
@dataclass(frozen=True)
class EvaluationRanges:
    """Profile evaluation ranges of eq (15) (m).

    Pinion roll length s is measured from N1, gear roll length u from N2
    (u = n1n2_m - s for the contact point at s on the line of action).
    """

    s_o_pinion_m: float
    s_f_pinion_m: float
    s_o_gear_m: float
    s_f_gear_m: float
    n1n2_m: float


def evaluation_ranges(geom) -> EvaluationRanges:
    """Active-profile evaluation ranges from a PairGeometry (gearfmu.gear.geometry).

    N1N2 = (rb1 + rb2) tan(alpha_w) = a_w sin(alpha_w) (length of the
    theoretical line of action between the tangent points).
    """
    n1n2 = (geom.rb1_m + geom.rb2_m) * math.tan(geom.alpha_w_rad)
    s_a, s_e = float(geom.s_start_m), float(geom.s_end_m)
    if not 0.0 <= s_a < s_e <= n1n2 * (1 + 1e-12):
        raise MeshingErrorInputError(
            f"s_start_m/s_end_m: need 0 <= s_A < s_E <= N1N2={n1n2!r}, got {s_a!r}, {s_e!r}")
    return EvaluationRanges(s_o_pinion_m=s_a, s_f_pinion_m=s_e,
                            s_o_gear_m=n1n2 - s_e, s_f_gear_m=n1n2 - s_a, n1n2_m=n1n2)


# ---------------------------------------------------------------- per-pair error
def pair_error_m(pair: GearPairSpec, ranges: EvaluationRanges, mesh_number, s_m,
                 pitch1_m: np.ndarray | None = None, pitch2_m: np.ndarray | None = None) -> np.ndarray:
    """Meshing error (m) of the pair(s) of mesh number(s) n at LOA position(s) s (from N1).

    e = e_alpha,pinion(tooth n mod z1; s) + e_alpha,gear(tooth n mod z2; N1N2 - s)
        + p_pinion(n mod z1) + p_gear(n mod z2).
    ``mesh_number`` and ``s_m`` broadcast.  ``pitch1_m``/``pitch2_m`` may pass
    precomputed :func:`pitch_position_errors_m`.
    """
    z1, z2 = pair.pinion.teeth, pair.gear.teeth
    d1, d2 = pair.pinion.deviations, pair.gear.deviations
    if pitch1_m is None:
        pitch1_m = pitch_position_errors_m(d1, z1)
    if pitch2_m is None:
        pitch2_m = pitch_position_errors_m(d2, z2)
    n, s = np.broadcast_arrays(np.asarray(mesh_number, dtype=np.int64), np.asarray(s_m, dtype=float))
    i1, i2 = tooth_indices(n, z1, z2)
    out = pitch1_m[i1] + pitch2_m[i2]
    u = ranges.n1n2_m - s
    for idx in np.unique(i1):
        m = i1 == idx
        out[m] += profile_deviation_m(s[m], d1.tooth(int(idx)), ranges.s_o_pinion_m, ranges.s_f_pinion_m)
    for idx in np.unique(i2):
        m = i2 == idx
        out[m] += profile_deviation_m(u[m], d2.tooth(int(idx)), ranges.s_o_gear_m, ranges.s_f_gear_m)
    return out


def slot_mesh_numbers(slots: int, n_mesh: int, points_per_mesh: int) -> Tuple[np.ndarray, np.ndarray]:
    """Mesh number held by each slot at each grid angle, and the angle since it entered.

    Grid: phi_i = i * mesh_period / points_per_mesh, i = 0 .. n_mesh*points_per_mesh - 1.
    Slot p at grid index i holds the latest mesh n = p (mod P) that entered at or
    before phi_i (periodic: mesh numbers are taken modulo n_mesh).  Returns
    (mesh_number (P, N) int, local index since entry (P, N) int, in grid steps).
    """
    if n_mesh % slots:
        raise MeshingErrorInputError(f"n_mesh: {n_mesh} is not a multiple of slots={slots}")
    i = np.arange(n_mesh * points_per_mesh)
    cur = i // points_per_mesh  # mesh that started most recently (any slot)
    p = np.arange(slots)[:, None]
    n = cur[None, :] - np.mod(cur[None, :] - p, slots)
    local = i[None, :] - n * points_per_mesh
    return np.mod(n, n_mesh), local


def slot_errors_m(pair: GearPairSpec, geom, slots: int, n_mesh: int, points_per_mesh: int) -> np.ndarray:
    """Meshing error of the pair in each slot over the table period (m), shape (P, N).

    The contact point moves along the line of action at rb1 per radian of
    pinion rotation: s = s_A + rb1 * (phi - phi_entry); outside the contact zone
    s is clamped to [s_A, s_E] (the error is held at its end value so that table
    interpolation stays smooth; the pair has k = 0 there).
    """
    ranges = evaluation_ranges(geom)
    n, local = slot_mesh_numbers(slots, n_mesh, points_per_mesh)
    dphi = geom.mesh_period_rad / points_per_mesh
    s = np.clip(geom.s_start_m + geom.rb1_m * local * dphi, geom.s_start_m, geom.s_end_m)
    return pair_error_m(pair, ranges, n, s)


def slot_slice_errors_m(pair: GearPairSpec, geom, slots: int, n_mesh: int, points_per_mesh: int,
                        slices: int) -> np.ndarray:
    """Meshing error seen by each face-width slice of the pair in each slot (m), shape (P, NS, N).

    Helical pairs (docs/helical.md): slice n of a pair meets the line of action
    lag_n = y_n tan(beta_b)/p_bt mesh periods after the leading face end
    (:func:`gearfmu.gear.stiffness.slice_lag_mesh_periods`), so at a given pinion angle
    it sees the profile deviation at s = s_A + rb1 (phi - phi_entry) - lag_n p_bt
    (clamped to [s_A, s_E] like :func:`slot_errors_m`); a slice crossing the entry or
    exit line sees it at the middle of its engaged part, as its stiffness does
    (:func:`gearfmu.gear.stiffness.engaged_slice_part`); pitch deviations are the
    same for every slice.  Spur pairs: every slice equals :func:`slot_errors_m`.
    """
    ranges = evaluation_ranges(geom)
    n, local = slot_mesh_numbers(slots, n_mesh, points_per_mesh)
    dphi = geom.mesh_period_rad / points_per_mesh
    lag = slice_lag_mesh_periods(geom, slices) if geom.helix_angle_rad != 0.0 else np.zeros(int(slices))
    s = geom.s_start_m + geom.rb1_m * local[:, None, :] * dphi - lag[None, :, None] * geom.base_pitch_m
    if geom.helix_angle_rad != 0.0:  # partly engaged slices: the middle of the engaged part
        frac, mid = engaged_slice_part(geom, slices, (s - geom.s_start_m) / geom.base_pitch_m)
        s = np.where(frac > 1e-12, geom.s_start_m + mid * geom.base_pitch_m, s)
    s = np.clip(s, geom.s_start_m, geom.s_end_m)
    nn = np.broadcast_to(n[:, None, :], s.shape)
    return pair_error_m(pair, ranges, nn, s)


def stiffness_weighted_pair_error_m(e_slice_m, k_slice_N_per_m) -> np.ndarray:
    """Pair error (P, N) from per-slice errors (P, NS, N), weighted by the slice stiffness.

    A pair whose slices are springs k_n at gaps e_n carries
    sum_n k_n (x - e_n) = k (x - e) with k = sum_n k_n and e = sum_n k_n e_n / k
    when all its engaged slices touch (docs/helical.md); where no slice of the
    pair is engaged the plain slice mean keeps the table smooth.
    """
    e = np.asarray(e_slice_m, dtype=float)
    k = np.asarray(k_slice_N_per_m, dtype=float)
    if e.shape != k.shape or e.ndim != 3:
        raise MeshingErrorInputError(f"k_slice_N_per_m: shape {k.shape} must equal e_slice_m {e.shape} (P, NS, N)")
    ks = k.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        w = (k * e).sum(axis=1) / np.where(ks > 0, ks, 1.0)
    return np.where(ks > 0, w, e.mean(axis=1))


# ----------------------------------------------------------- comprehensive error
def comprehensive_error_m(e_m: np.ndarray, in_contact: np.ndarray) -> np.ndarray:
    """Comprehensive (envelope) meshing error for the traditional model (m).

    With gearfmu's sign (positive = material deficit) the unloaded transmission
    error is set by the pair with the smallest gap, so
    e_comp(phi) = min over pairs in the contact zone of e_j(phi).  This is seed
    003's "superior envelope ... of the tooth pair with the larger meshing
    error" (Fig. 5) in a convention where the error is counted positive as
    interference (the pair that touches first); the two statements coincide.
    ``e_m``/``in_contact`` have the slot axis second to last: (..., P, N).
    Angles with no pair in contact fall back to the min over all slots.
    """
    e = np.asarray(e_m, dtype=float)
    mask = np.asarray(in_contact, dtype=bool)
    if e.shape != mask.shape:
        raise MeshingErrorInputError(f"in_contact: shape {mask.shape} differs from e_m {e.shape}")
    masked = np.where(mask, e, np.inf)
    out = masked.min(axis=-2)
    none = ~mask.any(axis=-2)
    if np.any(none):
        out = np.where(none, e.min(axis=-2), out)
    return out


# ----------------------------------------------------------------- lead crowning
def slice_centres_m(face_width_m: float, slices: int) -> np.ndarray:
    """Centres y_n of ``slices`` equal face-width slices, y in [-b/2, b/2] (m)."""
    if not (math.isfinite(face_width_m) and face_width_m > 0):
        raise MeshingErrorInputError(f"face_width_m: must be finite and > 0, got {face_width_m!r}")
    if int(slices) != slices or slices < 1:
        raise MeshingErrorInputError(f"slices: must be a positive integer, got {slices!r}")
    return -0.5 * face_width_m + (np.arange(slices) + 0.5) * face_width_m / slices


def lead_crowning_m(crowning_m: float, face_width_m: float, slices: int) -> np.ndarray:
    """E_pc of each slice (m), Zhao et al. 2022 eq (16): parabolic lead crowning,
    E_pc(y) = C_b (2y/b)^2 at the slice centres (C_b at both face ends, 0 at the
    centre; positive = material removed = gap)."""
    if not math.isfinite(crowning_m) or crowning_m < 0:
        raise MeshingErrorInputError(f"lead_crowning_m: must be finite and >= 0, got {crowning_m!r}")
    y = slice_centres_m(face_width_m, slices)
    return crowning_m * (2.0 * y / face_width_m) ** 2


def pair_lead_crowning_m(pair: GearPairSpec, slices: int) -> np.ndarray:
    """E_pc per slice of the pair (m): the two flanks' crowning adds along the
    normal, C_b = C_b,pinion + C_b,gear, over the common face width
    b = min(b1, b2)."""
    b = min(pair.pinion.face_width_m, pair.gear.face_width_m)
    c = pair.pinion.deviations.lead_crowning_m + pair.gear.deviations.lead_crowning_m
    return lead_crowning_m(c, b, slices)
