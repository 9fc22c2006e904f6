"""Temperature stiffness of a spur tooth pair (He & Yang 2023) and
the oil-temperature viscosity law for the EHL film.  SI units; temperatures in degC
(differences in K = degC).

He & Yang 2023 model (its section 3)
------------------------------
A tooth pair in the *standard* state (temperature t0) carries the normal load
F_n with the elastic deformation x = F_n/k along the line of action (k: pair
stiffness; k_i: single-tooth stiffness of the pinion, i = 1, and of the gear,
i = 2; eq 2-4).

* **Thermal expansion** (t >= t0, eq 5-22).  The free normal thermal expansion
  Delta x_pi of each flank is restrained at the contact point.  Energy balance
  (eq 9-11) with Delta x_TS = Delta x_T / 2 (eq 8) gives

      x_T = sqrt(x^2 + S/(2k)),   S = k_1 Delta x_p1^2 + k_2 Delta x_p2^2   (eq 14)
      x_Ti = (k/k_i) x_T                                                     (eq 15)
      k_T = F_n/x_T,  k_Ti = F_n/x_Ti                                       (eq 17-18)
      1/k_T = 1/k + 1/k_TS,  1/k_Ti = 1/k_i + 1/k_TSi                        (eq 21-22)

  (eq 12-14 as printed lost their brackets in the text extraction; the form above
  is the one that follows from eq 8 and eq 11 and that reproduces the seed's
  Tables 2-3, see docs/thermal.md.)
* **Cold shrinkage** (t < t0, eq 23-26): the shrinkage Delta x_Si of each flank
  adds to the elastic deformation, x_Si = x_i + Delta x_Si, x_S = x + sum_i Delta x_Si,
  k_S = F_n/x_S, k_Si = F_n/x_Si.
* **Full range** (eq 27-28): expansion above t0, shrinkage below, a spring in
  series with the standard stiffness.  The stiffness is largest at t0 and falls
  on both sides ("low-high-low", Fig. 5).

CHOICES where the seed leaves gaps (also in docs/thermal.md):

1. *Pinion and gear in different states* (one above t0, one below; the seed only
   treats both on one side): the expanding teeth feed the energy term S, the
   shrinking teeth add their shrinkage in series:
   x_T = sqrt(x^2 + S_exp/(2k)) + sum_shrinking Delta x_Si,
   x_Ti = (k/k_i) sqrt(x^2 + S_exp/(2k)) + Delta x_Si (0 when tooth i expands).
   Both limits are exactly seed eq 14-15 and eq 23.
2. *k with a Hertz spring and the shared foundation*: the seed's pair stiffness is
   the series sum of its two single-tooth values (its Tables 2-3 satisfy
   1/k = 1/k_1 + 1/k_2 to 5 digits).  Ours has a Hertz spring and, in multi-pair
   contact, the shared-foundation correction.  Eq 8 (Delta x_TS = Delta x_T/2) holds
   for any chain of series springs whose compliances sum to 1/k, so we keep the
   formulas with k = our pair stiffness and k_i = our single-tooth stiffness
   (bending + shear + axial + fillet foundation): the teeth store the thermal
   energy, every spring of the chain is compressed.
3. *Free flank deformation Delta x_pi* (the seed takes it from its ref [27], Luo,
   Li, Fu et al. 2020, J. Braz. Soc. Mech. Sci. Eng. 42:150, which could not be
   read here).  Two laws, :func:`free_flank_deformation_m`:

   * ``"radial_tangential"`` (default): the radial expansion alpha dT r_K of the
     contact point about the gear centre plus the growth alpha dT h_K of the tooth
     half-thickness about the tooth centre line, each projected on the flank
     normal (the line of action):  Delta x_p = alpha dT (r_K sin a_K + h_K cos a_K)
     = alpha dT (r_b tan a_K + h_K cos a_K), h_K = r_K sin psi_K the half chordal
     thickness at r_K, a_K the pressure angle of the flank at K.  Reconstructed
     from the seed's own numbers: with the load of its Table 4 (80 kW at
     2000 rpm, F_n = T_1/r_b1 = 10 037 N for pair I) it reproduces all six
     single-tooth shrinkage compliances of pair I in Table 2 to 0.03 % -- no other
     simple law we tried comes within 10 % (docs/thermal.md).
   * ``"homogeneous"``: a free body heated uniformly is scaled about its centre by
     (1 + alpha dT); the involute flank then moves along its normal by
     alpha dT (r_K . n) = alpha dT r_b tan a_K, the distance N_iK from the base
     tangent point (derived here from the uniform scaling of a free body).
4. *Load on a pair in multi-pair contact* (:func:`thermal_slot_stiffness`): the
   quasi-static share F_n k_slot / sum k_slot of the total normal load
   T_1/r_b1 (the seed loads one pair with the whole F_n at every key point; so
   does :func:`key_point_stiffness`).
5. *Temperature along the line of action* (seed Fig. 6): a bulk temperature per
   gear as a function of the normalised coordinate of He & Yang 2023
   Gamma_K = N1K/N1C - 1 (:class:`TemperatureProfile`); the flank deformation at a
   contact point uses the local temperature of each flank there.

Viscosity (:func:`oil_dynamic_viscosity_Pas`): Walther's equation of ASTM D341,
log10 log10(nu + 0.7) = A - B log10(T/K), through two kinematic viscosities
(:func:`gearfmu.ehl.lubricant.walther_kinematic_viscosity_cSt`), times the density;
CHOICE: the oil density is held at its scene value (its thermal expansion,
about 0.07 %/K, is left out: it changes eta0 by less than 3 % over 40 K, against
a factor 8 in the kinematic viscosity between 40 and 100 degC).  CHOICE: the
pressure-viscosity coefficient alpha is kept at its scene value at every oil
temperature (no alpha(T) law in the seeds or the scene; film thickness goes as
alpha^0.54 in Dowson-Higginson, so a falling alpha would thin the hot film a
little more).  The tables' oil temperature axis (``[thermal] axis_quantity =
"oil"``, :func:`gearfmu.assembly.precompute.oil_axis_eta0_Pas`) feeds eta0(T) of this law
into the lubricated contact model's ``ContactEnvironment`` and rebuilds the
tables at every axis temperature (docs/thermal.md "Oil temperature axis").

Scene -> state (:func:`thermal_state_from_scene`): without an axis, a pinion /
gear temperature or profile different from the standard temperature changes
the tables at that one state (He & Yang 2023 eq 27-28, every torque row;
docs/thermal.md "One temperature without an axis").
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple, Union

import numpy as np

from ..common.checks import finite_number
from ..common.vocabulary import FLANK_LAWS, OIL_ALPHA_LAWS, THERMAL_AXIS_QUANTITIES
from .gearpair import GearPairSpec, MeshModelOptions
from .geometry import PairGeometry, pair_geometry
from .stiffness import tooth_compliance_m_per_N, pair_stiffness_at_N_per_m, slot_stiffness
from ..ehl.lubricant import Lubricant, walther_kinematic_viscosity_cSt



class ThermalError(ValueError):
    """Bad input to the temperature-stiffness functions (message names the field)."""


def _finite(name: str, v: float) -> float:
    return finite_number(name, v, error=ThermalError)


def _temperature(name: str, t_C) -> np.ndarray:
    t = np.asarray(t_C, dtype=float)
    if not np.all(np.isfinite(t)):
        raise ThermalError(f"{name}: temperatures must be finite, got {t_C!r}")
    if np.any(t <= -273.15):
        raise ThermalError(f"{name}: temperature below absolute zero, got {t_C!r}")
    return t


# ================================================================ temperature along the LOA
def gamma_from_s(geom: PairGeometry, s_m) -> np.ndarray:
    """The normalised LOA coordinate of He & Yang 2023, Gamma_K = (N1K - N1C)/N1C (1) of the
    contact point at LOA position ``s_m`` (m from N1): -1 at N1, 0 at the pitch
    point C."""
    return np.asarray(s_m, dtype=float) / geom.s_pitch_m - 1.0


def s_from_gamma(geom: PairGeometry, gamma) -> np.ndarray:
    """Inverse of :func:`gamma_from_s`: LOA position (m from N1)."""
    return (np.asarray(gamma, dtype=float) + 1.0) * geom.s_pitch_m


@dataclass(frozen=True)
class TemperatureProfile:
    """Bulk temperature of one gear's flank along the line of action (He & Yang 2023 Fig. 6b).

    ``gamma``: ascending He & Yang 2023 normalised coordinates Gamma_K (1);
    ``temperature_C``: temperatures there (degC).  Linear in between, constant
    beyond the ends.
    """

    gamma: Tuple[float, ...]
    temperature_C: Tuple[float, ...]

    def __post_init__(self):
        g = np.asarray(self.gamma, dtype=float)
        t = np.asarray(self.temperature_C, dtype=float)
        if g.ndim != 1 or g.size < 1:
            raise ThermalError("gamma: needs at least one point")
        if t.shape != g.shape:
            raise ThermalError(f"temperature_C: needs one value per gamma point ({g.size}), got {t.size}")
        if not np.all(np.isfinite(g)):
            raise ThermalError(f"gamma: must be finite, got {self.gamma!r}")
        if g.size > 1 and np.any(np.diff(g) <= 0):
            raise ThermalError(f"gamma: must be strictly ascending, got {self.gamma!r}")
        _temperature("temperature_C", t)

    def at_gamma(self, gamma) -> np.ndarray:
        """Temperature (degC) at normalised coordinates ``gamma``."""
        return np.interp(np.asarray(gamma, dtype=float), np.asarray(self.gamma, float),
                         np.asarray(self.temperature_C, float))

    def at_s(self, geom: PairGeometry, s_m) -> np.ndarray:
        """Temperature (degC) at LOA positions ``s_m`` (m from N1)."""
        return self.at_gamma(gamma_from_s(geom, s_m))

    def mean_C(self, geom: PairGeometry, n: int = 2001) -> float:
        """Mean temperature (degC) over the path of contact A..E (uniform in s)."""
        s = np.linspace(geom.s_start_m, geom.s_end_m, n)
        t = self.at_s(geom, s)
        return float(np.sum(0.5 * (t[1:] + t[:-1]) * np.diff(s)) / (s[-1] - s[0]))


#: a gear's bulk temperature: uniform (degC) or a profile along the line of action
Temperature = Union[float, TemperatureProfile]


def flank_temperature_C(temp: Temperature, geom: PairGeometry, s_m) -> np.ndarray:
    """Temperature (degC) of a flank at LOA positions ``s_m`` (uniform or profile)."""
    s = np.asarray(s_m, dtype=float)
    if isinstance(temp, TemperatureProfile):
        return temp.at_s(geom, s)
    return np.full(s.shape, float(_temperature("temperature_C", temp)))


# ================================================================ free flank deformation
def free_flank_deformation_m(geom: PairGeometry, which: int, s_m, delta_T_K, alpha_per_K: float,
                             law: str = "radial_tangential") -> np.ndarray:
    """Free (unrestrained) thermal deformation (m) of the flank of gear ``which``
    (1 pinion, 2 gear) along its normal at the contact point of LOA position
    ``s_m`` (m from N1), for a temperature rise ``delta_T_K`` (K, array or scalar,
    negative = cooling) and expansion coefficient ``alpha_per_K`` (1/K).

    Positive = the flank moves towards the mating flank (expansion).  ``law``:
    ``"radial_tangential"`` alpha dT (r_b tan a_K + h_K cos a_K) (reconstructed
    He & Yang 2023 ref [27], see the module doc) or ``"homogeneous"`` alpha dT r_b tan a_K
    (uniform scaling about the gear centre).
    """
    if which not in (1, 2):
        raise ThermalError(f"which: must be 1 (pinion) or 2 (gear), got {which!r}")
    if law not in FLANK_LAWS:
        raise ThermalError(f"law: must be one of {FLANK_LAWS}, got {law!r}")
    a = _finite("alpha_per_K", alpha_per_K)
    if a < 0:
        raise ThermalError(f"alpha_per_K: must be >= 0, got {alpha_per_K!r}")
    dT = np.asarray(delta_T_K, dtype=float)
    if not np.all(np.isfinite(dT)):
        raise ThermalError(f"delta_T_K: must be finite, got {delta_T_K!r}")
    s = np.asarray(s_m, dtype=float)
    roll = geom.roll_length_at(which, s)                 # N_i K = r_b tan a_K
    if np.any(roll < -1e-12 * geom.loa_length_m):
        raise ThermalError(f"s_m: contact below the base circle of gear {which}")
    roll = np.maximum(roll, 0.0)
    if law == "homogeneous":
        length = roll
    else:
        rb = geom.gear_values(which)["rb"]
        r = np.hypot(rb, roll)
        h = r * np.sin(geom.half_tooth_angle(which, r))  # half chordal thickness at r_K
        length = roll + h * (rb / r)                     # cos a_K = r_b / r_K
    return a * dT * length


# ================================================================ He & Yang 2023 eq 5-28
@dataclass(frozen=True)
class TemperatureStiffness:
    """Temperature stiffness of a tooth pair (He & Yang 2023 eq 27-28), N/m, and the
    thermal compliances added in series (m/N): ``k_N_per_m`` pair c_0,
    ``k1_N_per_m`` / ``k2_N_per_m`` pinion / gear single tooth c_i,
    ``compliance_m_per_N`` = 1/k_TS or 1/k_SS of the pair, ``compliance1_m_per_N``,
    ``compliance2_m_per_N`` of each tooth."""

    k_N_per_m: np.ndarray
    k1_N_per_m: np.ndarray
    k2_N_per_m: np.ndarray
    compliance_m_per_N: np.ndarray
    compliance1_m_per_N: np.ndarray
    compliance2_m_per_N: np.ndarray


def temperature_stiffness(k_N_per_m, k1_N_per_m, k2_N_per_m, free1_m, free2_m,
                          normal_load_N) -> TemperatureStiffness:
    """He & Yang 2023 eq (12)-(28): temperature stiffness of a pair and its teeth.

    ``k_N_per_m``: standard pair stiffness k; ``k1_N_per_m``, ``k2_N_per_m``:
    standard single-tooth stiffness of pinion and gear; ``free1_m``,
    ``free2_m``: free normal thermal deformation of each flank (m, positive =
    expansion above the standard temperature, negative = shrinkage,
    :func:`free_flank_deformation_m`); ``normal_load_N``: F_n (N, > 0) on the pair.
    Arrays broadcast.  Mixed states (one tooth expanding, one shrinking): see
    CHOICE 1 of the module doc.
    """
    k, k1, k2, p1, p2, F = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        k_N_per_m, k1_N_per_m, k2_N_per_m, free1_m, free2_m, normal_load_N)))
    for name, v in (("k_N_per_m", k), ("k1_N_per_m", k1), ("k2_N_per_m", k2), ("normal_load_N", F)):
        if not np.all(np.isfinite(v)) or np.any(v <= 0):
            raise ThermalError(f"{name}: must be finite and > 0")
    for name, v in (("free1_m", p1), ("free2_m", p2)):
        if not np.all(np.isfinite(v)):
            raise ThermalError(f"{name}: must be finite")
    x = F / k                                           # eq 2-4
    e1, e2 = np.maximum(p1, 0.0), np.maximum(p2, 0.0)   # expanding teeth (eq 9)
    s1, s2 = np.maximum(-p1, 0.0), np.maximum(-p2, 0.0)  # shrinking teeth (eq 23)
    S = k1 * e1 * e1 + k2 * e2 * e2
    q = S / (2.0 * k)
    X = np.sqrt(x * x + q)                              # eq 14
    dX = q / (X + x)                                    # eq 13, Delta x_TS = X - x without cancellation
    # thermal compliances (eq 19-22, 25): delta = (x_T - x)/F_n with x_T = X + shrinkage (eq 14, 23),
    # x_Ti = (k/k_i) X + shrinkage_i (eq 15, 23)
    c = (dX + s1 + s2) / F
    c1 = ((k / k1) * dX + s1) / F
    c2 = ((k / k2) * dX + s2) / F
    # k_T = F/x_T = 1/(1/k + delta), written k/(1 + k delta) so that delta = 0 returns k exactly
    return TemperatureStiffness(
        k_N_per_m=k / (1.0 + k * c), k1_N_per_m=k1 / (1.0 + k1 * c1), k2_N_per_m=k2 / (1.0 + k2 * c2),
        compliance_m_per_N=c, compliance1_m_per_N=c1, compliance2_m_per_N=c2)


# ================================================================ our standard stiffness at points
def single_tooth_stiffness_N_per_m(pair: GearPairSpec, geom: PairGeometry, which: int, s_m,
                                   width_m: Optional[float] = None, foundation: bool = True) -> np.ndarray:
    """Standard single-tooth stiffness k_i (N/m) of gear ``which`` at LOA positions
    ``s_m``: bending + shear + axial compression (+ Sainsot fillet foundation) of
    :func:`gearfmu.gear.stiffness.tooth_compliance_m_per_N`, over ``width_m`` (default
    the face width)."""
    b = min(pair.pinion.face_width_m, pair.gear.face_width_m) if width_m is None else width_m
    gear = pair.pinion if which == 1 else pair.gear
    c = tooth_compliance_m_per_N(gear, geom, which, np.atleast_1d(np.asarray(s_m, float)), b)
    comp = c["bending"] + c["shear"] + c["axial"] + (c["foundation"] if foundation else 0.0)
    return 1.0 / comp


@dataclass(frozen=True)
class ThermalState:
    """Bulk temperatures of pinion and gear (uniform degC or
    :class:`TemperatureProfile`) around the standard temperature (degC)."""

    pinion: Temperature
    gear: Temperature
    standard_temperature_C: float = 30.0

    def free_deformations_m(self, pair: GearPairSpec, geom: PairGeometry, s_m,
                            law: str = "radial_tangential") -> Tuple[np.ndarray, np.ndarray]:
        """(pinion, gear) free flank deformations (m) at LOA positions ``s_m``."""
        t0 = float(_temperature("standard_temperature_C", self.standard_temperature_C))
        out = []
        for which, temp, g in ((1, self.pinion, pair.pinion), (2, self.gear, pair.gear)):
            dT = flank_temperature_C(temp, geom, s_m) - t0
            out.append(free_flank_deformation_m(geom, which, s_m, dT, g.material.thermal_expansion_per_K, law))
        return out[0], out[1]


def key_points_m(geom: PairGeometry) -> dict:
    """The key points of He & Yang 2023 on the LOA (m from N1): meshing-in A, pitch C, meshing-out E."""
    return {"meshing-in": geom.s_start_m, "pitch": geom.s_pitch_m, "meshing-out": geom.s_end_m}


def key_point_stiffness(pair: GearPairSpec, state: ThermalState, normal_load_N: float, s_m,
                        geom: Optional[PairGeometry] = None, *, law: str = "radial_tangential",
                        standard: Optional[Tuple] = None, hertz: bool = True) -> TemperatureStiffness:
    """Temperature stiffness of ONE tooth pair carrying the whole ``normal_load_N``
    (N) at LOA positions ``s_m`` (He & Yang 2023 Tables 2-3 convention).

    ``standard``: optional (k, k1, k2) arrays (N/m) to use instead of our standard
    stiffness (to isolate the thermal model, e.g. the seed's own values); by
    default k1, k2 from :func:`single_tooth_stiffness_N_per_m` and k from
    :func:`gearfmu.gear.stiffness.pair_stiffness_at_N_per_m` (with Hertz when
    ``hertz``, else the series sum of the two teeth as in the seed).
    """
    geom = pair_geometry(pair) if geom is None else geom
    s = np.atleast_1d(np.asarray(s_m, dtype=float))
    if standard is None:
        k1 = single_tooth_stiffness_N_per_m(pair, geom, 1, s)
        k2 = single_tooth_stiffness_N_per_m(pair, geom, 2, s)
        k = pair_stiffness_at_N_per_m(pair, geom, s) if hertz else 1.0 / (1.0 / k1 + 1.0 / k2)
    else:
        k, k1, k2 = (np.asarray(v, dtype=float) for v in standard)
    p1, p2 = state.free_deformations_m(pair, geom, s, law)
    return temperature_stiffness(k, k1, k2, p1, p2, _finite("normal_load_N", normal_load_N))


# ================================================================ tables: per-temperature slot stiffness
@dataclass(frozen=True)
class ThermalSlotStiffness:
    """Per-slot temperature mesh stiffness on the pinion-angle grid.

    ``temperatures_C`` (NTemp,): the axis (uniform bulk temperature of both gears,
    or the labels of ``states``); ``k_N_per_m`` (NTemp, P, n): pair stiffness of
    each slot (0 out of contact), the standard one at the standard temperature;
    ``k_standard_N_per_m`` (P, n); ``phi_rad`` (n,); ``torque_Nm`` the pinion torque.
    """

    temperatures_C: np.ndarray
    k_N_per_m: np.ndarray
    k_standard_N_per_m: np.ndarray
    phi_rad: np.ndarray
    torque_Nm: float
    standard_temperature_C: float


def thermal_slot_stiffness(pair: GearPairSpec, opts: Optional[MeshModelOptions] = None, *,
                           torque_Nm: float, temperatures_C: Sequence[float] = (),
                           states: Sequence[ThermalState] = (), standard_temperature_C: float = 30.0,
                           slots: Optional[int] = None, n_per_mesh: int = 64,
                           law: str = "radial_tangential",
                           geom: Optional[PairGeometry] = None) -> ThermalSlotStiffness:
    """Per-slot tooth-pair stiffness (N/m) at a list of temperatures, for the
    tables' temperature axis (docs/thermal.md "Temperature axis").

    Either ``temperatures_C`` (uniform bulk temperature of both gears, degC; the
    axis) or ``states`` (one :class:`ThermalState` per axis point; the axis then
    holds the mean pinion temperature of each state).  ``torque_Nm``: pinion torque
    (N m, > 0) -- the seed's temperature stiffness depends on the load; each pair
    carries its quasi-static share F_n k_slot/sum k_slot of F_n = T/r_b1 (CHOICE 4).
    The standard slot stiffness is :func:`gearfmu.gear.stiffness.slot_stiffness`
    (``opts``, ``slots``, ``n_per_mesh`` as there); each contact point adds the
    thermal compliance of :func:`temperature_stiffness` in series.
    """
    geom = pair_geometry(pair) if geom is None else geom
    T = _finite("torque_Nm", torque_Nm)
    if T <= 0:
        raise ThermalError(f"torque_Nm: must be > 0 (the temperature stiffness of seed 004 needs a load), got {torque_Nm!r}")
    t0 = float(_temperature("standard_temperature_C", standard_temperature_C))
    if len(temperatures_C) and len(states):
        raise ThermalError("temperatures_C, states: give one of them, not both")
    if len(states):
        sts = list(states)
        for st in sts:
            if not isinstance(st, ThermalState):
                raise ThermalError(f"states: must hold ThermalState objects, got {type(st).__name__}")
        axis = np.array([st.pinion.mean_C(geom) if isinstance(st.pinion, TemperatureProfile)
                         else float(st.pinion) for st in sts])
    else:
        axis = _temperature("temperatures_C", temperatures_C).ravel()
        if axis.size == 0:
            raise ThermalError("temperatures_C: needs at least one temperature")
        if axis.size > 1 and np.any(np.diff(axis) <= 0):
            raise ThermalError(f"temperatures_C: must be strictly ascending, got {list(temperatures_C)!r}")
        sts = [ThermalState(float(t), float(t), t0) for t in axis]
    ss = slot_stiffness(pair, geom, opts, slots, n_per_mesh)
    k_std = ss.k_N_per_m
    s = ss.s_m
    mask = np.isfinite(s) & (k_std > 0)
    K = k_std.sum(axis=0)
    F_pair = np.where(mask, (T / geom.rb1_m) * k_std / np.where(K > 0, K, 1.0)[None, :], 0.0)
    sv = s[mask]
    k1 = single_tooth_stiffness_N_per_m(pair, geom, 1, sv)
    k2 = single_tooth_stiffness_N_per_m(pair, geom, 2, sv)
    out = np.zeros((len(sts),) + k_std.shape)
    for j, st in enumerate(sts):
        p1, p2 = st.free_deformations_m(pair, geom, sv, law)
        ts = temperature_stiffness(k_std[mask], k1, k2, p1, p2, F_pair[mask])
        out[j][mask] = ts.k_N_per_m
    return ThermalSlotStiffness(temperatures_C=axis, k_N_per_m=out, k_standard_N_per_m=k_std,
                                phi_rad=ss.phi_rad, torque_Nm=T, standard_temperature_C=t0)


# ================================================================ lubricant temperature
def oil_kinematic_viscosity_m2_s(nu40_m2_s: float, nu100_m2_s: float, temperature_C) -> np.ndarray:
    """Kinematic viscosity (m^2/s) at ``temperature_C`` (degC) from the values at
    40 and 100 degC by Walther's equation (ASTM D341),
    :func:`gearfmu.ehl.lubricant.walther_kinematic_viscosity_cSt`."""
    n40 = _finite("nu40_m2_s", nu40_m2_s)
    n100 = _finite("nu100_m2_s", nu100_m2_s)
    if not (n40 > n100 > 0):
        raise ThermalError(f"nu40_m2_s, nu100_m2_s: need nu40 > nu100 > 0, got {nu40_m2_s!r}, {nu100_m2_s!r}")
    t = _temperature("temperature_C", temperature_C)
    f = np.vectorize(lambda tc: walther_kinematic_viscosity_cSt(n40 * 1e6, n100 * 1e6, float(tc)), otypes=[float])
    return 1e-6 * f(t)


def oil_dynamic_viscosity_Pas(nu40_m2_s: float, nu100_m2_s: float, density_kg_m3: float,
                              temperature_C) -> np.ndarray:
    """eta0 (Pa s) of the EHL solver at oil temperature ``temperature_C`` (degC):
    Walther / ASTM D341 kinematic viscosity times the (constant, CHOICE) density."""
    rho = _finite("density_kg_m3", density_kg_m3)
    if rho <= 0:
        raise ThermalError(f"density_kg_m3: must be > 0, got {density_kg_m3!r}")
    return rho * oil_kinematic_viscosity_m2_s(nu40_m2_s, nu100_m2_s, temperature_C)


# ================================================================ [thermal] options -> state
@dataclass(frozen=True)
class ThermalOptions:
    """Thermal options of a pair's tables (He & Yang 2023; docs/thermal.md), degC: a scene's
    ``[thermal]`` section (:mod:`gearfmu.scene.sections`).

    ``pinion_temperature_C`` / ``gear_temperature_C``: uniform bulk temperature
    (None = the standard temperature); ``*_profile_gamma`` / ``*_profile_C``:
    a bulk temperature along the line of action over the normalised
    coordinate Gamma_K of He & Yang 2023 (overrides the uniform value when given);
    ``temperature_axis_C``: temperatures of the tables' temperature axis
    (empty = no axis); ``flank_law``: free flank deformation law of
    :func:`gearfmu.gear.thermal.free_flank_deformation_m`; ``axis_quantity``: what
    the axis is (:data:`THERMAL_AXIS_QUANTITIES`): "bulk" the bulk temperature of
    both gears (He & Yang 2023 stiffness, FMU input ``bulk_temperature``), "oil" the
    oil temperature (eta0 of a lubricated contact model, input
    ``oil_temperature``), "bulk_and_oil" both at one temperature (input
    ``gearbox_temperature``); ``lubricant``: the scene's ``[lubricant]`` (its
    viscosity-temperature law), attached by the scene reader when the axis
    involves the oil.  Without an axis, ``pinion_temperature_C`` /
    ``gear_temperature_C`` / the profiles change the tables (He & Yang 2023 eq 27-28
    at that state); with a "bulk" or "bulk_and_oil" axis the axis sets the gear
    temperatures and these keys must be absent; with an "oil" axis they give
    the gears' state at every oil temperature (docs/thermal.md).
    ``oil_alpha``: the pressure-viscosity coefficient along an oil axis:
    "roelands" (Roelands 1966, constant Z: alpha(T) from eta0(T),
    :func:`gearfmu.ehl.lubricant.roelands_alpha_at_viscosity_Pa_inv`) or
    "constant" (the ``[lubricant]`` value at every temperature).
    """

    standard_temperature_C: float = 30.0
    pinion_temperature_C: Optional[float] = None
    gear_temperature_C: Optional[float] = None
    pinion_profile_gamma: Tuple[float, ...] = ()
    pinion_profile_C: Tuple[float, ...] = ()
    gear_profile_gamma: Tuple[float, ...] = ()
    gear_profile_C: Tuple[float, ...] = ()
    temperature_axis_C: Tuple[float, ...] = ()
    flank_law: str = FLANK_LAWS[0]
    axis_quantity: str = THERMAL_AXIS_QUANTITIES[0]
    oil_alpha: str = OIL_ALPHA_LAWS[0]
    lubricant: Optional[Lubricant] = None


def thermal_state_from_scene(options: ThermalOptions) -> ThermalState:
    """:class:`ThermalState` of thermal options (a scene's ``[thermal]`` section): a profile when
    its points are given, else the uniform temperature, else the standard temperature."""
    t0 = float(options.standard_temperature_C)

    def one(role):
        g, t = getattr(options, f"{role}_profile_gamma"), getattr(options, f"{role}_profile_C")
        if len(g):
            return TemperatureProfile(tuple(g), tuple(t))
        u = getattr(options, f"{role}_temperature_C")
        return t0 if u is None else float(u)

    return ThermalState(one("pinion"), one("gear"), t0)
