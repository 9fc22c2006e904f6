"""Plain-data description of a spur or helical gear pair (SI units throughout).

These small frozen dataclasses are the input of every physics module
(geometry, stiffness, errors, loaded mesh).  The scene parser
(:mod:`gearfmu.scene.reader`) builds them from a TOML file and converts the
scene's engineering units (mm, deg, GPa, um, rpm) to SI here.

Conventions
-----------
* Gear 1 is the *pinion* (driving), gear 2 the *gear* (driven).
* Angles in rad, lengths in m, moduli in Pa, densities in kg/m^3,
  torques in N*m, speeds in rad/s.
* Deviations follow Xu et al. 2022 eq (15): profile form deviation ``f_fa`` (m),
  profile slope deviation ``f_Ha`` (m), ``f_r`` sine periods over the
  profile evaluation range.  A *positive* deviation is a material deficit
  along the flank normal, i.e. it opens the gap that the mesh must close:
  the pair comes into contact when the dynamic transmission error x exceeds
  e + b (Xu et al. 2022 eq 6).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple


@dataclass(frozen=True)
class Material:
    """Isotropic elastic material of one gear body."""

    youngs_modulus_Pa: float = 206e9
    poisson_ratio: float = 0.3
    density_kg_m3: float = 7850.0
    thermal_expansion_per_K: float = 1.13e-5


@dataclass(frozen=True)
class ToothDeviation:
    """Deviation of one tooth's active drive flank (Xu et al. 2022 eq 15).

    ``profile_form_m`` is f_fa, ``profile_slope_m`` is f_Ha, ``form_periods``
    is f_r.  ``pitch_m`` is the single pitch deviation of this tooth along the
    line of action (positive = tooth lags, i.e. a material deficit at contact).
    """

    profile_form_m: float = 0.0
    profile_slope_m: float = 0.0
    form_periods: float = 2.0
    pitch_m: float = 0.0

    @property
    def is_zero(self) -> bool:
        return self.profile_form_m == 0.0 and self.profile_slope_m == 0.0 and self.pitch_m == 0.0


@dataclass(frozen=True)
class GearDeviations:
    """Deviations of all teeth of one gear.

    ``default`` applies to every tooth; ``per_tooth`` maps a tooth index
    (0-based) to its own :class:`ToothDeviation`.  ``lead_crowning_m`` is the
    lead crowning amount C_b (material removed at both face ends relative to
    the face centre, parabolic across the face; Zhao et al. 2022 eq 16's E_pc).
    """

    default: ToothDeviation = ToothDeviation()
    per_tooth: Tuple[Tuple[int, ToothDeviation], ...] = ()
    lead_crowning_m: float = 0.0

    def tooth(self, index: int) -> ToothDeviation:
        for i, dev in self.per_tooth:
            if i == index:
                return dev
        return self.default

    @property
    def teeth_differ(self) -> bool:
        """True when some tooth differs from the default one."""
        return any(dev != self.default for _, dev in self.per_tooth)

    @property
    def is_zero(self) -> bool:
        return (self.default.is_zero and all(d.is_zero for _, d in self.per_tooth)
                and self.lead_crowning_m == 0.0)


@dataclass(frozen=True)
class GearSpec:
    """One involute spur gear (Zhao et al. 2022 Table 1 / He & Yang 2023 Table 1 style)."""

    teeth: int
    module_m: float
    pressure_angle_rad: float
    face_width_m: float
    profile_shift: float = 0.0
    addendum_coefficient: float = 1.0
    tip_clearance_coefficient: float = 0.25
    hub_radius_m: Optional[float] = None  # radius of the gear-body bore / hub (Sainsot r_int)
    material: Material = Material()
    inertia_kgm2: Optional[float] = None  # None: solid disc between hub and reference pitch radius (assembly.precompute.disc_inertia_kgm2)
    deviations: GearDeviations = GearDeviations()
    # Helical gears (docs/helical.md): reference helix angle beta (rad, 0 = spur, [0, pi/4]);
    # with beta != 0, ``module_m``, ``pressure_angle_rad``, ``profile_shift``,
    # ``addendum_coefficient`` and ``tip_clearance_coefficient`` are NORMAL-section values
    # (m_n, alpha_n, x_n, h_an*, c_n*: the basic rack of the cutting tool, ISO 21771 / ISO 53);
    # the transverse ones follow in gearfmu.gear.geometry.  ``helix_hand`` "right" | "left": the
    # two gears of an external pair have opposite hands and the same beta.
    helix_angle_rad: float = 0.0
    helix_hand: str = "right"


@dataclass(frozen=True)
class GearPairSpec:
    """A pinion and a gear in mesh.

    ``backlash_m`` is the *total* circumferential-play measured along the
    line of action; the dead zone of Xu et al. 2022 eq (6) uses b = backlash/2.
    ``center_distance_m`` None means the zero-backlash operating centre
    distance from the profile shifts (inv alpha_w equation).
    """

    pinion: GearSpec
    gear: GearSpec
    backlash_m: float = 0.0
    center_distance_m: Optional[float] = None


@dataclass(frozen=True)
class MeshModelOptions:
    """Modelling choices of the quasi-static mesh (TVMS and errors)."""

    contact_model: str = "hertz"  # "hertz" (this issue); later "smooth_ehl", "rough_ehl", "fractal_mixed"
    slices: int = 1
    foundation: bool = True  # Sainsot et al. (2004) fillet-foundation stiffness
    # Ma et al. (2016) shared-foundation correction (Zhao et al. 2022 eq 11) with lambda = 1; off by default:
    # docs/physics_stiffness.md, 'Why the correction is off by default'
    shared_foundation_correction: bool = False
