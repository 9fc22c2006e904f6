"""Per-section readers of a scene: each turns one TOML table (already checked key by key
by :class:`~gearfmu.scene.validate.Reader`) into its SI object and checks the keys of
that table against each other.

==============  ===============================================================
Reader          Builds
==============  ===============================================================
gear_spec       [gears.<role>] + [gears] + [material] -> GearSpec
deviations      [deviations.<role>] and its [[...tooth]] rows -> GearDeviations
lubricant       [lubricant] -> Lubricant
thermal         [thermal] -> ThermalOptions
roughness       [roughness] -> gearfmu.contact.base.RoughnessSpec
==============  ===============================================================

Problems are added to the reader with their key paths; a section with a problem
gives None.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Dict, List, Optional, Tuple

from ..contact.base import RoughnessSpec
from ..contact.roughness import SEED000_LEVELS
from ..ehl.lubricant import walther_kinematic_viscosity_cSt
from ..gear.gearpair import GearDeviations, GearSpec, Material, ToothDeviation
from .options import Lubricant, ThermalOptions
from .schema import TOOTH_KEYS
from .validate import Reader, describe, sub, suggest

__all__ = ["gear_spec", "deviations", "lubricant", "thermal", "roughness"]

def gear_spec(r: Reader, data: Any, role: str, shared: Dict[str, Any], mat: Dict[str, Any],
               dev: Optional[GearDeviations]) -> Optional[GearSpec]:
    g = r.table(sub(sub(data, "gears"), role), f"gears.{role}", required=True)
    vals = {k: g[k] if g.get(k) is not None else mat[k] for k in
            ("youngs_modulus_GPa", "poisson_ratio", "density_kg_m3", "thermal_expansion_per_K")}
    if any(v is None for v in vals.values()) or g["teeth"] is None:
        return None
    needed = ("profile_shift", "addendum_coefficient", "tip_clearance_coefficient")
    if any(g[k] is None for k in needed) or any(shared[k] is None for k in
                                                 ("module_mm", "pressure_angle_deg", "face_width_mm")):
        return None
    material = Material(youngs_modulus_Pa=vals["youngs_modulus_GPa"], poisson_ratio=vals["poisson_ratio"],
                        density_kg_m3=vals["density_kg_m3"], thermal_expansion_per_K=vals["thermal_expansion_per_K"])
    m = shared["module_mm"]
    hub = g["hub_radius_mm"]
    beta = shared.get("helix_angle_deg") or 0.0
    hand = shared.get("hand") or "right"
    if role == "gear" and beta != 0.0:
        hand = "left" if hand == "right" else "right"
    if hub is not None:
        root = m * (g["teeth"] / (2.0 * math.cos(beta)) - g["addendum_coefficient"] - g["tip_clearance_coefficient"]
                    + g["profile_shift"])
        if hub >= root:
            r.add(f"gears.{role}.hub_radius_mm",
                  f"must be smaller than the root radius {root * 1e3:.4g} mm, got {hub * 1e3:g}")
            return None
    return GearSpec(teeth=g["teeth"], module_m=m, pressure_angle_rad=shared["pressure_angle_deg"],
                    face_width_m=shared["face_width_mm"], profile_shift=g["profile_shift"],
                    addendum_coefficient=g["addendum_coefficient"],
                    tip_clearance_coefficient=g["tip_clearance_coefficient"], hub_radius_m=hub,
                    material=material, inertia_kgm2=g["inertia_kgm2"],
                    deviations=dev if dev is not None else GearDeviations(),
                    helix_angle_rad=beta, helix_hand=hand)


def deviations(r: Reader, data: Any, role: str, teeth: Optional[int]) -> Optional[GearDeviations]:
    """Read [deviations.<role>] and its [[deviations.<role>.tooth]] rows into
    a :class:`GearDeviations` (SI); ``teeth`` None = tooth count invalid
    (then only the per-key checks run)."""
    path = f"deviations.{role}"
    raw = sub(sub(data, "deviations"), role)
    n_before = len(r.problems)
    d = r.table(raw, path)
    rows: List[Tuple[str, Dict[str, Any]]] = []
    traw = sub(raw, "tooth")
    if traw is not None:
        if not isinstance(traw, list) or not all(isinstance(t, dict) for t in traw):
            r.add(f"{path}.tooth", f"must be an array of tables [[{path}.tooth]], got {describe(traw)}")
            traw = []
        valid = [k.name for k in TOOTH_KEYS]
        units = {k.name: k.unit for k in TOOTH_KEYS}
        for i, t in enumerate(traw):
            p = f"{path}.tooth[{i}]"
            for name in t:
                if name not in valid:
                    r.add(f"{p}.{name}", "unknown key" + suggest(name, valid, units))
            vals: Dict[str, Any] = {}
            for k in TOOTH_KEYS:
                if k.name in t:
                    vals[k.name] = r.value(f"{p}.{k.name}", k, t[k.name])
                elif k.required:
                    r.add(f"{p}.{k.name}", "missing (required)")
                    vals[k.name] = None
            rows.append((p, vals))
    pitch = d.get("pitch_um")
    if teeth is not None and pitch is not None and len(pitch) not in (0, teeth):
        r.add(f"{path}.pitch_um", f"must have one value per tooth ({teeth}) or be empty, got {len(pitch)} values")
    seen: Dict[int, str] = {}
    for p, vals in rows:
        idx = vals["index"]
        if idx is not None and teeth is not None:
            if idx >= teeth:
                r.add(f"{p}.index", f"must be an integer in [0, {teeth - 1}] (the gear has {teeth} teeth), got {idx}")
            elif idx in seen:
                r.add(f"{p}.index", f"tooth {idx} is already given by {seen[idx]}")
            else:
                seen[idx] = p
        if "pitch_um" in vals and pitch:
            r.add(f"{p}.pitch_um", f"tooth pitch given twice: {path}.pitch_um already lists every tooth")
    if len(r.problems) > n_before or teeth is None:
        return None
    default = ToothDeviation(profile_form_m=d["profile_form_um"], profile_slope_m=d["profile_slope_um"],
                             form_periods=d["form_periods"], pitch_m=0.0)
    overrides = {vals["index"]: vals for _, vals in rows}
    fields = (("profile_form_m", "profile_form_um"), ("profile_slope_m", "profile_slope_um"),
              ("form_periods", "form_periods"), ("pitch_m", "pitch_um"))
    per_tooth = []
    for i in range(teeth):
        dev = replace(default, pitch_m=pitch[i]) if pitch else default
        o = overrides.get(i)
        if o:
            dev = replace(dev, **{f: o[key] for f, key in fields if key in o})
        if dev != default:
            per_tooth.append((i, dev))
    return GearDeviations(default=default, per_tooth=tuple(per_tooth), lead_crowning_m=d["lead_crowning_um"])


def lubricant(r: Reader, data: Any) -> Optional[Lubricant]:
    """Read ``[lubricant]`` (None when absent or invalid): eta0 given directly, or from the
    kinematic viscosities at 40 and 100 degC (Walther / ASTM D341) times the density."""
    got = r.section(data, "lubricant")
    if got is None:
        return None
    raw, lu = got
    has_eta = "eta0_Pas" in raw
    has_nu = ("kinematic_viscosity_40C_cSt" in raw, "kinematic_viscosity_100C_cSt" in raw)
    if has_eta and any(has_nu):
        r.add("lubricant", "give either eta0_Pas or the kinematic viscosities "
                           "(kinematic_viscosity_40C_cSt and kinematic_viscosity_100C_cSt), not both")
        return None
    if not has_eta and not all(has_nu):
        r.add("lubricant", "needs eta0_Pas, or both kinematic_viscosity_40C_cSt and "
                           "kinematic_viscosity_100C_cSt")
        return None
    nu40 = nu100 = None
    if has_eta:
        eta = lu["eta0_Pas"]
    else:
        nu40, nu100 = lu["kinematic_viscosity_40C_cSt"], lu["kinematic_viscosity_100C_cSt"]
        if not nu100 < nu40:
            r.add("lubricant.kinematic_viscosity_100C_cSt",
                  f"must be smaller than kinematic_viscosity_40C_cSt ({nu40 * 1e6:g}), got {nu100 * 1e6:g}")
            return None
        try:
            eta = 1e-6 * walther_kinematic_viscosity_cSt(nu40 * 1e6, nu100 * 1e6, lu["temperature_C"]) \
                * lu["density_kg_m3"]
        except (OverflowError, ValueError):
            eta = float("nan")
        if not (math.isfinite(eta) and eta > 0):
            r.add("lubricant.temperature_C", f"the viscosity law gives no usable viscosity at {lu['temperature_C']:g} degC")
            return None
    return Lubricant(name=lu["name"], dynamic_viscosity_Pas=eta,
                     pressure_viscosity_Pa_inv=lu["pressure_viscosity_GPa_inv"],
                     density_kg_m3=lu["density_kg_m3"], temperature_C=lu["temperature_C"],
                     kinematic_viscosity_40C_m2_s=nu40, kinematic_viscosity_100C_m2_s=nu100)


def thermal(r: Reader, data: Any) -> Optional[ThermalOptions]:
    """Read ``[thermal]`` (None when absent or invalid); checks profile lengths and order."""
    got = r.section(data, "thermal")
    if got is None:
        return None
    th = got[1]
    n0 = len(r.problems)
    for role in ("pinion", "gear"):
        g, t = th[f"{role}_profile_gamma"], th[f"{role}_profile_C"]
        if len(g) != len(t):
            r.add(f"thermal.{role}_profile_C", f"needs one temperature per {role}_profile_gamma point "
                                               f"({len(g)}), got {len(t)}")
        elif any(b <= a for a, b in zip(g, g[1:])):
            r.add(f"thermal.{role}_profile_gamma", f"must be strictly ascending, got {list(g)!r}")
    ax = th["temperature_axis_C"]
    if any(b <= a for a, b in zip(ax, ax[1:])):
        r.add("thermal.temperature_axis_C", f"must be strictly ascending, got {list(ax)!r}")
    if len(r.problems) > n0:
        return None
    return ThermalOptions(**th)


def roughness(r: Reader, data: Any) -> Optional[RoughnessSpec]:
    """Read ``[roughness]`` into the contact models' :class:`RoughnessSpec` (None when absent
    or invalid): level 1-4 takes D and G from Zhao et al. 2022 Table 2, level 0 the given ones."""
    got = r.section(data, "roughness")
    if got is None:
        return None
    raw, ro = got
    n0 = len(r.problems)
    level = ro["level"]
    if level == 0:
        for k in ("fractal_dimension", "G_nm"):
            if ro[k] is None:
                r.add(f"roughness.{k}", "required when roughness.level = 0")
        if len(r.problems) > n0:
            return None
        D, G = ro["fractal_dimension"], ro["G_nm"]
    else:
        for k in ("fractal_dimension", "G_nm"):
            if k in raw:
                r.add(f"roughness.{k}", f"only with roughness.level = 0 (level {level} takes D and G "
                                        "from seed 000 Table 2)")
        if len(r.problems) > n0:
            return None
        D, G = SEED000_LEVELS[level].D, SEED000_LEVELS[level].G_m
    if ro["film_position_nodes"] == 1:
        r.add("roughness.film_position_nodes", "must be 0 (every table position) or >= 2 (interpolation nodes)")
        return None
    if ro["film_transient"] != "off" and ro["film_position_nodes"] == 0:
        r.add("roughness.film_transient", f"{ro['film_transient']!r} is stored on the film grid; needs "
                                          "film_position_nodes >= 2 (got 0)")
        return None
    return RoughnessSpec(D=D, G_m=G, seed=ro["seed"], f_max_per_m=ro["max_frequency_per_mm"],
                         level=level, on_failure=ro["on_film_failure"],
                         full_film_parameter=ro["full_film_parameter"],
                         position_nodes=ro["film_position_nodes"], film_transient=ro["film_transient"])
