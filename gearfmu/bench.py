"""Hard cases of the dynamic model and the speed-against-error benchmark.

``hard_case(name)`` returns ``(tables, kwargs)`` for :func:`gearfmu.dynamics.native.simulate`
(and :func:`gearfmu.dynamics.reference.simulate_reference`, which takes the same
arguments): the hard cases of the dynamic model, built from textbook tables (the
rectangular-wave TVMS of :mod:`gearfmu.tables.synthetic`, Xu et al. 2022 Table 1 gear data)
and from a computed scene.  Inputs only -- no results are stored here.

``accuracy_benchmark()`` runs, on one case and in one process, every
integrator that :func:`gearfmu.dynamics.native.simulate` offers
(:data:`gearfmu.common.vocabulary.INTEGRATORS`) at several internal steps, the FMU (fmpy) at several
communication steps, and scipy ``solve_ivp`` DOP853 and Radau (event-located,
:mod:`gearfmu.dynamics.reference`) at several tolerances, and reports wall time and
error against the tight reference: ``gearfmu bench accuracy --json [--png P]``.

The planetary cases (section "planetary stages" below): ``LIN_PARKER_1999`` (Lin & Parker's
published example system), ``lp_stage`` / ``lp_model`` and ``planetary_case(name)`` -- the hard
cases of the planetary solver's tests and benchmark (tests/unit/planetary/test_planetary_*.py,
benchmarks/bench_planetary.py).

Errors are relative: RMS (or max) over the communication instants of
(method - reference), divided by the reference's peak-to-peak range, for the
dynamic transmission error (dte) and the total mesh force.
"""
from __future__ import annotations

import json
import math
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Callable, Dict, Optional

import numpy as np

from .assembly.planetary_lumped import LumpedPlanetary, lumped_stage
from .common.settings import RunSettings
from .common.vocabulary import DEFAULT_DAMPING_MODEL, DEFAULT_INTEGRATOR, INTEGRATORS
from .dynamics.native import simulate
from .dynamics.reference import simulate_reference
from .fmu.compare import output_names, run_fmu
from .fmu.pythonfmu_build import build_fmu
from .gear.planetary_set import PlanetErrors
from .gearbox.model import Mesh, Shaft
from .pipeline import compute_tables, load
from .planetary.model import build_drivetrain
from .tables.synthetic import KB_BACKLASH_HALF_M, rectangular_wave_tables

__all__ = ["HARD_CASES", "hard_case", "case_settings", "rel_errors", "accuracy_benchmark", "plot_pareto",
           "native_integrators"]


def _kb(**kw):
    """Rectangular-wave TVMS on the Xu et al. 2022 Table 1 gears (50/50 teeth, eps 1.7547),
    every engaged pair 2.5e8 N/m (k_double = 2 k_single), half backlash 68 um."""
    args = dict(k_single_N_per_m=2.5e8, backlash_half_m=KB_BACKLASH_HALF_M)
    args.update(kw)
    return rectangular_wave_tables(**args)


def tent_error(amplitude_m: float):
    """Meshing error of a pair over its engagement u in [0, 1): amplitude*(1 - |2u - 1|),
    0 at meshing-in and -out (continuous), peak mid-engagement; kinks only at u = 0, 1/2, 1."""
    return lambda slot, u: amplitude_m * (1.0 - np.abs(2.0 * u - 1.0))


def omega_n(tables) -> float:
    """sqrt(k_mean/m_e) (rad/s), Xu et al. 2022 eq 7."""
    return math.sqrt(tables.k_mean_N_per_m / tables.equivalent_mass_kg)


def speed_for(tables, Omega_h: float) -> float:
    """Pinion speed (rad/s) with mesh frequency Omega_h * omega_n (Xu et al. 2022 eq 7)."""
    return Omega_h * omega_n(tables) * tables.mesh_period_rad / (2.0 * math.pi)


def _kw(tables, Omega_h, torque, zeta, mesh_periods, comm_per_mesh=4, **extra):
    w1 = speed_for(tables, Omega_h)
    Tm = tables.mesh_period_rad / w1
    H = Tm / comm_per_mesh
    # start 0.31 of a table step past a node, so that the communication instants do not fall
    # on table nodes (where de/dphi, hence the output force, is one-sided; docs/dynamics_validation.md)
    kw = dict(stop_time_s=mesh_periods * comm_per_mesh * H, comm_step_s=H, pinion_torque_Nm=torque,
              pinion_speed_start_rad_s=w1, damping_ratio=zeta, pinion_angle_start_rad=0.31 * tables.dphi_rad)
    kw.update(extra)
    return kw


def _heavy():
    t = _kb()
    return t, _kw(t, 0.6, 2000.0, 0.05, 30)


def _single_sided():
    t = _kb()
    return t, _kw(t, 0.9, 60.0, 0.03, 30)


def _double_sided():
    t = _kb(backlash_half_m=10e-6, pair_error_m=tent_error(20e-6))
    return t, _kw(t, 0.5, 5.0, 0.05, 30)


def _low_damping():
    t = _kb(pair_error_m=tent_error(5e-6))
    return t, _kw(t, 0.95, 340.0, 0.01, 30)


def _hcr():
    t = _kb(contact_ratio=2.4, slots=5, mesh_periods=5, pair_error_m=tent_error(3e-6))
    return t, _kw(t, 0.7, 340.0, 0.02, 30)


def _fast():
    t = _kb(pair_error_m=tent_error(5e-6))
    return t, _kw(t, 2.0, 340.0, 0.02, 40)


def _torque_steps():
    t = _kb(pair_error_m=tent_error(5e-6))
    kw = _kw(t, 0.7, 340.0, 0.03, 36)
    n = int(round(kw["stop_time_s"] / kw["comm_step_s"]))
    kw["pinion_torque_Nm"] = np.where(np.arange(n) < n // 3, 340.0, np.where(np.arange(n) < 2 * n // 3, 60.0, 900.0))
    return t, kw


def _computed():
    """The default scene's computed tables (Zhao et al. 2022 Table 1 pair) at its operating point."""
    scene = load(None)
    t = compute_tables(scene)
    w1 = scene.operating.speed_rad_s
    Tm = t.mesh_period_rad / w1
    H = Tm / 4
    return t, dict(stop_time_s=40 * H, comm_step_s=H, pinion_torque_Nm=scene.operating.torque_Nm,
                   pinion_speed_start_rad_s=w1, damping_ratio=scene.fmu.damping_ratio,
                   damping_model=scene.solver.damping_model)


HARD_CASES: Dict[str, Callable] = {
    "heavy_load": _heavy,
    "single_sided_impacts": _single_sided,
    "double_sided_impacts": _double_sided,
    "low_damping_resonance": _low_damping,
    "high_contact_ratio": _hcr,
    "omega_h_2": _fast,
    "torque_steps": _torque_steps,
    "computed_default_scene": _computed,
}


def hard_case(name: str):
    """(tables, simulate kwargs) of a hard case; ValueError naming unknown cases."""
    if name not in HARD_CASES:
        raise ValueError(f"case: {name!r} unknown; choose one of {sorted(HARD_CASES)}")
    return HARD_CASES[name]()


def rel_errors(res, ref) -> dict:
    """RMS and max of (res - ref) over the communication instants, relative to the
    reference's peak-to-peak range, for dte and mesh_force; nan if res has NaN."""
    out = {}
    for key, name in (("dte", "dte"), ("force", "mesh_force")):
        a, b = np.asarray(getattr(res, name) if not isinstance(res, dict) else res[name], float), \
            np.asarray(getattr(ref, name), float)
        n = min(len(a), len(b))
        d = a[:n] - b[:n]
        rng = float(np.ptp(b[:n])) or 1.0
        out[f"{key}_rel_rms_err"] = float(np.sqrt(np.mean(d ** 2)) / rng)
        out[f"{key}_rel_max_err"] = float(np.max(np.abs(d)) / rng)
    return out


def native_integrators():
    """``("integrator", names)``: the argument of :func:`gearfmu.dynamics.native.simulate` that
    selects the integrator and the names it takes (:data:`gearfmu.common.vocabulary.INTEGRATORS`)."""
    return "integrator", list(INTEGRATORS)


def case_settings(kw: dict):
    """(:class:`gearfmu.common.settings.RunSettings`, pinion torque input) of a hard case's
    keyword arguments (:func:`hard_case`): the settings' start torque is the input's first value."""
    torque = kw["pinion_torque_Nm"]
    start = float(torque) if np.ndim(torque) == 0 else float(np.asarray(torque, dtype=float)[0])
    settings = RunSettings(stop_time_s=kw["stop_time_s"], output_interval_s=kw["comm_step_s"],
                           damping_ratio=kw["damping_ratio"],
                           damping_model=kw.get("damping_model", DEFAULT_DAMPING_MODEL),
                           pinion_speed_start_rad_s=kw["pinion_speed_start_rad_s"],
                           pinion_angle_start_rad=kw.get("pinion_angle_start_rad", 0.0), pinion_torque_start_Nm=start)
    return settings, torque


def accuracy_benchmark(case: str = "single_sided_impacts", *, substeps=(4, 8, 16, 32, 64, 128, 256),
                       fmu_comm_mesh_periods=(0.25, 1.0, 5.0, 10.0), fmu_substeps: int = 64,
                       rtols=(1e-4, 1e-6, 1e-8), ref_rtol: float = 1e-11, mesh_periods: Optional[int] = None,
                       progress: bool = True) -> dict:
    """Speed against error on one hard case (see module docstring); returns a dict with
    ``rows`` (method, setting, wall_s, errors) and the reference's settings."""
    def say(msg):
        if progress:
            print(f"bench: {msg}", file=sys.stderr, flush=True)

    tables, kw = hard_case(case)
    if mesh_periods is not None:
        kw["stop_time_s"] = kw["comm_step_s"] * 4 * mesh_periods
    H = kw["comm_step_s"]
    Tm = 4 * H
    say(f"case {case}: {int(round(kw['stop_time_s'] / H))} comm steps of {H:.3g} s; reference rtol {ref_rtol:g}")
    settings, torque = case_settings(kw)
    t0 = time.perf_counter()
    ref = simulate_reference(tables, settings, pinion_torque_Nm=torque, rtol=ref_rtol, steps_per_period=128)
    ref_wall = time.perf_counter() - t0
    rows = []
    pname, integrators = native_integrators()
    simulate(tables, settings, stop_time_s=H, max_step_s=H, pinion_torque_Nm=torque if np.ndim(torque) == 0
             else np.asarray(torque)[:1])  # JIT warm-up
    for integ in integrators:
        for n in substeps:
            best = math.inf
            for _ in range(3):  # best of three (shared machine)
                t0 = time.perf_counter()
                res = simulate(tables, settings, max_step_s=H / n, integrator=integ, pinion_torque_Nm=torque)
                best = min(best, time.perf_counter() - t0)
            rows.append(dict(method=f"native-{integ}", setting=f"h=H/{n}", step_s=H / n, wall_s=best,
                             **rel_errors(res, ref)))
            say(f"native {integ} H/{n}: {rows[-1]['dte_rel_rms_err']:.2e}")

    with tempfile.TemporaryDirectory() as wd:
        hmax = H / fmu_substeps
        say("building the FMU (C kernel, once; the communication step is the master's choice)")

        fmu = build_fmu(tables, Path(wd) / "bench.fmu", settings, model_name="bench", max_step_s=hmax,
                        integrator=DEFAULT_INTEGRATOR)  # the FMU as built by default
        for m in fmu_comm_mesh_periods:
            Hc = m * Tm
            nsteps = kw["stop_time_s"] / Hc
            if abs(nsteps - round(nsteps)) > 1e-9 or round(nsteps) < 1:
                continue
            run = run_fmu(fmu, stop_time_s=kw["stop_time_s"], comm_step_s=Hc, names=output_names(tables.slots))
            stride = int(round(Hc / H))
            sub = type("R", (), {})()
            sub.dte = ref.dte[::stride]
            sub.mesh_force = ref.mesh_force[::stride]
            rows.append(dict(method=f"fmu-{DEFAULT_INTEGRATOR}", setting=f"comm={m:g} Tm, h=H/{fmu_substeps}",
                             step_s=hmax, wall_s=run.wall_s,
                             **rel_errors({"dte": run.columns["dte"], "mesh_force": run.columns["mesh_force"]}, sub)))
            say(f"fmu comm {m:g} Tm: {rows[-1]['dte_rel_rms_err']:.2e}, {run.wall_s:.3f} s")
    for method in ("DOP853", "Radau"):
        for rt in rtols:
            t0 = time.perf_counter()
            res = simulate_reference(tables, settings, pinion_torque_Nm=torque, rtol=rt, method=method,
                                     steps_per_period=8)
            wall = time.perf_counter() - t0
            rows.append(dict(method=f"solve_ivp-{method}", setting=f"rtol={rt:g}", wall_s=wall,
                             **rel_errors(res, ref)))
            say(f"{method} rtol {rt:g}: {rows[-1]['dte_rel_rms_err']:.2e}, {wall:.2f} s")
    return {"case": case, "comm_step_s": H, "stop_time_s": kw["stop_time_s"],
            "reference": {"method": "DOP853 event-located (gearfmu.dynamics.reference)", "rtol": ref_rtol,
                          "steps_per_period": 128, "wall_s": ref_wall, "segments": ref.info["segments"],
                          "events": ref.info["events"]},
            "integrator_parameter": pname, "rows": rows}


def plot_pareto(report: dict, png_path) -> Path:
    """Wall time against dte RMS error, one marker series per method (log-log)."""
    import matplotlib  # matplotlib: only for the optional accuracy plot

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: only for the optional accuracy plot

    fig, ax = plt.subplots(figsize=(7, 5))
    methods = []
    for r in report["rows"]:
        if r["method"] not in methods:
            methods.append(r["method"])
    for m in methods:
        rs = [r for r in report["rows"] if r["method"] == m and math.isfinite(r.get("wall_s", math.nan))
              and r.get("dte_rel_rms_err", 0) > 0]
        if rs:
            ax.loglog([r["dte_rel_rms_err"] for r in rs], [r["wall_s"] for r in rs], "o-", label=m)
    ax.set_xlabel("dte RMS error / dte range (vs event-located reference)")
    ax.set_ylabel("wall time (s)")
    ax.set_title(f"speed against error: {report['case']}, {report['stop_time_s'] * 1e3:.3g} ms simulated")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    png_path = Path(png_path)
    png_path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(png_path, dpi=120)
    plt.close(fig)
    return png_path


def accuracy_table(rep: dict) -> list:
    """The lines of ``gearfmu bench accuracy``: what the errors are relative to, then one row per run."""
    ref = rep["reference"]
    lines = [f"case {rep['case']}, {rep['stop_time_s'] * 1e3:.4g} ms simulated, communication step "
             f"{rep['comm_step_s']:.3g} s; reference: {ref['method']}, rtol {ref['rtol']:g}",
             "errors are RELATIVE: RMS (rms) or largest (max) |run - reference| over the communication "
             "instants, divided by the reference's range (max - min over the run) of the same signal "
             "(dte: dynamic transmission error; F: total mesh force)",
             f"{'method':<22}{'setting':<36}{'wall [s]':>10}{'dte rms':>11}{'dte max':>11}{'F rms':>11}"]
    for r in rep["rows"]:
        lines.append(f"{r['method']:<22}{r['setting']:<36}{r['wall_s']:>10.4f}"
                     f"{r.get('dte_rel_rms_err', math.nan):>11.2e}{r.get('dte_rel_max_err', math.nan):>11.2e}"
                     f"{r.get('force_rel_rms_err', math.nan):>11.2e}")
    return lines


def main_accuracy(args) -> int:
    rep = accuracy_benchmark(args.case, progress=True)  # progress on stderr
    if args.png:
        plot_pareto(rep, args.png)
        rep["png"] = str(args.png)
    if args.json:
        print(json.dumps(rep, indent=1))
    else:
        for line in accuracy_table(rep):
            print(line)
    return 0


# ================================================================ planetary stages
# The cases of the planetary tests and benchmark (tests/unit/planetary/test_planetary_*.py,
# benchmarks/bench_planetary.py): inputs only.
#
# Cases of the planetary tests and benchmark: inputs only (no results here).
#
# * :data:`LIN_PARKER_1999` -- the example system of J. Lin, R. G. Parker, J. Vib. Acoust. 121 (1999)
#   316-321, Table 1, entered as published (masses and I/r^2 in kg, mesh, bearing and torsional
#   support stiffness in N/m, pressure angle 24.6 deg of both meshes; the sun and carrier have no
#   torsional support).  The table gives no tooth counts; teeth and radii only set the kinematics
#   and the mesh frequency here, not the frequencies: sun 24, planet 36, ring 96 teeth (z_r = z_s +
#   2 z_p keeps alpha_r = alpha_s; (z_s + z_r)/N an integer for N = 3, 4, 5; CHOICE) and the sun base
#   radius of the table's 77.4 mm base diameter (its planet and ring diameters, 100.3 and 275.0 mm, do
#   not fit 24.6 deg on both meshes and are not used).  The model's frequencies are checked against
#   the published ones (docs/planetary.md "Verification against published values").
# * :func:`lp_stage`, :func:`lp_model`: that system as a stage and as a standalone drivetrain
#   (motor on the sun, load on the carrier, the ring held by its published torsional support).
# * :func:`planetary_case`: hard cases of the native solver against its reference (``contact_loss``:
#   three planets, rectangular-wave stiffness, 15 um backlash, sequential phases; the sun torque drops
#   from 60 to 2 N m after two mesh periods (the load balancing it at every step): the released
#   mesh deflections make every mesh lose contact now and then;
#   ``position_error``: four planets on a floating sun, planet 1's pin 20 um behind its place;
#   ``two_stage``: the power entering at the carrier of a planetary stage followed by a parallel stage,
#   so the planetary meshes run their tables backwards).

#: Lin & Parker (1999), Table 1 (see the module docstring for the source of the values)
LIN_PARKER_1999 = dict(
    mass_kg=dict(sun=0.4, ring=2.35, carrier=5.43, planet=0.66),
    inertia_over_r2_kg=dict(sun=0.39, ring=3.0, carrier=6.29, planet=0.61),
    mesh_stiffness_sun_N_per_m=5e8, mesh_stiffness_ring_N_per_m=5e8,
    bearing_N_per_m=dict(sun=1e8, ring=1e8, carrier=1e8, planet=1e8),
    support_N_per_m=1e9,                       # k_ru; k_su = k_cu = 0
    pressure_angle_sun_rad=math.radians(24.6),
)
#: tooth counts and sun base radius chosen here (module docstring)
LP_TEETH = (24, 36, 96)
LP_SUN_BASE_RADIUS_M = 0.0387


def lp_parameters(planets: int, **overrides) -> LumpedPlanetary:
    """Lin & Parker's example system with ``planets`` planets (LumpedPlanetary; ``overrides`` replace
    fields, e.g. contact ratios, teeth, errors)."""
    zs, zp, zr = LP_TEETH
    p = LumpedPlanetary(planets=planets, teeth_sun=zs, teeth_planet=zp, teeth_ring=zr,
                        base_radius_sun_m=LP_SUN_BASE_RADIUS_M, **LIN_PARKER_1999)
    return replace(p, **overrides)


def lp_stage(planets: int, name: str = "lp", **kw):
    """Lin & Parker's system as a :class:`gearfmu.tables.planetary.PlanetaryStage` (ring held)."""
    stage_kw = {k: kw.pop(k) for k in ("held", "model", "mesh_damping_ratio", "damping_model",
                                       "bearing_damping_ratio") if k in kw}
    return lumped_stage(name, lp_parameters(planets, **kw), **stage_kw)


def lp_model(planets: int, **kw):
    """The standalone stage: motor on the sun, load on the carrier."""
    st = lp_stage(planets, **kw)
    return build_drivetrain(planetaries=[st], motor=f"{st.name}.sun", load=f"{st.name}.carrier")


def run_kwargs(model, stage_mesh: str, speed: float, torque, mesh_periods: int, comm_per_mesh: int = 8, **extra):
    """Arguments of gearfmu.planetary.native.simulate: ``mesh_periods`` periods of mesh ``stage_mesh``
    at the motor speed ``speed`` (rad/s), ``comm_per_mesh`` communication steps per period, the motor
    torque ``torque`` (N m), the motor angle 0.013 rad at the start (off the table nodes)."""
    m = model.mesh_names.index(stage_mesh)
    T = float(model.mesh_tables[m].mesh_period_rad) / (abs(float(model.angle_ref[m])) * speed)
    kw = dict(stop_time_s=mesh_periods * T, comm_step_s=T / comm_per_mesh, motor_torque_Nm=torque,
              motor_speed_start_rad_s=speed, motor_angle_start_rad=0.013)
    kw.update(extra)
    return kw


def _contact_loss(mesh_periods):
    st = lp_stage(3, teeth_sun=25, teeth_planet=29, teeth_ring=83, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  backlash_half_m=15e-6, gamma_rs=0.3)
    m = build_drivetrain(planetaries=[st], shafts=[Shaft("input_shaft", "motor", "lp.sun", 3e3, 0.02)],
                         parts={"motor": 2e-3}, motor="motor", load="lp.carrier")
    kw = run_kwargs(m, "lp.sun_planet[1]", 400.0, 60.0, mesh_periods)
    t_drop = 16.0 * kw["comm_step_s"]          # two sun-mesh periods
    kw["motor_torque_Nm"] = lambda t: 60.0 if t < t_drop else 2.0
    return m, kw


def _position_error(mesh_periods):
    st = lp_stage(4, teeth_sun=21, teeth_planet=23, teeth_ring=67, contact_ratio_sun=1.6, contact_ratio_ring=1.7,
                  bearing_N_per_m=dict(sun=0.0, ring=1e8, carrier=1e8, planet=1e8),
                  planet_errors=(PlanetErrors(0.0, -20e-6), PlanetErrors(), PlanetErrors(), PlanetErrors()))
    m = build_drivetrain(planetaries=[st], motor="lp.sun", load="lp.carrier")
    return m, run_kwargs(m, "lp.sun_planet[1]", 300.0, 60.0, mesh_periods)


def two_stage_model():
    """Carrier-driven planetary stage (ring held, sun out) followed by a parallel stage."""
    st = lp_stage(3, teeth_sun=24, teeth_planet=36, teeth_ring=96, contact_ratio_sun=1.5, contact_ratio_ring=1.6)
    par = rectangular_wave_tables(4e8, contact_ratio=1.6, points_per_mesh=32, teeth_pinion=23, teeth_gear=41,
                                  base_radius_pinion_m=0.03, base_radius_gear_m=0.03 * 41 / 23,
                                  inertia_pinion_kgm2=2e-4, inertia_gear_kgm2=2e-3)
    return build_drivetrain([Mesh("par", par, 0.05)], [st],
                            [Shaft("input_shaft", "motor", "lp.carrier", 2e5, 0.02),
                             Shaft("intermediate_shaft", "lp.sun", "par.pinion", 3e3, 0.02),
                             Shaft("output_shaft", "par.gear", "load", 2e4, 0.02)],
                            {"motor": 0.5, "load": 0.02}, motor="motor", load="load")


def _two_stage(mesh_periods):
    m = two_stage_model()
    return m, run_kwargs(m, "lp.sun_planet[1]", 40.0, 200.0, mesh_periods)


PLANETARY_CASES: Dict[str, Callable] = {
    "contact_loss": _contact_loss,
    "position_error": _position_error,
    "two_stage": _two_stage,
}


def planetary_case(name: str, mesh_periods: int = 20):
    """(model, simulate kwargs) of a hard case over ``mesh_periods`` sun-mesh periods."""
    if name not in PLANETARY_CASES:
        raise ValueError(f"case: {name!r} unknown; choose one of {sorted(PLANETARY_CASES)}")
    return PLANETARY_CASES[name](int(mesh_periods))
