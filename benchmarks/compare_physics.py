"""Bit-for-bit record of the physics functions, for refactorings of the EHL solvers, the table
assembly, the synthetic tables and the gearbox reference that must not change a result.

    python benchmarks/compare_physics.py run CHECKOUT OUT.npz [--only GROUP,...]
    python benchmarks/compare_physics.py diff A.npz B.npz

``run`` imports gearfmu from CHECKOUT (checked) and stores every output array of these calls in
OUT.npz (no pickle; strings as unicode arrays):

* ``steady``: :func:`gearfmu.ehl.solve_line_contact` -- smooth films at Moes M, L (Roelands and
  Barus, fast path and the piezoviscous corner plan), dimensional inputs at several loads and
  speeds, a warm start, the full-multigrid start stopped at the discretisation error, caller
  tolerances and relaxation options, rough films (one step, amplitude steps, warm-started from the
  smooth film, the coupled Newton off), and the failure paths: a stall (the cycle limit, fail-fast
  rules 1 and 2), the coupled Newton as last resort, a film collapse and input errors -- of a
  failure the exception's type, message (the wall time cut off), residual, attempts, skipped
  retries, problem and history;
* ``transient``: :func:`gearfmu.ehl.solve_line_contact_transient` -- harmonic waviness on the
  characteristic, BDF2 and BDF1 schemes, the smooth start, the sub-step rescue, given relaxation
  settings, a gear flank slice;
* ``tables``: the MeshTables of scenes derived from the default scene: as it is (Hertz), the
  rough-EHL contact at roughness level 2, the smooth EHL film, a bulk temperature axis, one thermal
  state, an oil temperature axis; the helical pair of examples/scenes/seed001_table1.toml;
* ``direct``: :func:`gearfmu.assembly.direct_tvms.direct_mesh_stiffness` for every model;
* ``synthetic``: :func:`gearfmu.tables.synthetic.tables_from_arrays` and
  :func:`rectangular_wave_tables`;
* ``gearbox``: :func:`gearfmu.gearbox.reference.simulate_reference` on the hard cases and on the
  example gearbox examples/scenes/gearbox_two_stage.toml.

Wall and CPU times are left out.  ``diff`` prints every array that differs (or is in one file
only) and exits with status 1 when any does, 0 when every array is identical bit for bit.
Record the unchanged tree once (``git archive HEAD | tar -x -C DIR``) and compare each step of a
refactoring with it.
"""
from __future__ import annotations

import argparse
import inspect
import json
import math
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

GROUPS = ("steady", "transient", "tables", "direct", "synthetic", "gearbox")

#: smooth steady films at Moes (M, L): the fast path, high load, the piezoviscous corner
STEADY_ML = [(5.0, 0.0), (20.0, 5.0), (100.0, 10.0), (500.0, 10.0), (50.0, 20.0), (1000.0, 5.0)]
#: dimensional case (Venner & Lubrecht's oil on steel) at several loads and speeds
DIM = dict(R_m=0.02, E_Pa=2.26e11, eta0_Pas=0.04, alpha_Pa_inv=2.2e-8)
DIM_LOADS_SPEEDS = [(1e5, 1.0), (3e5, 2.0), (1e6, 5.0), (3e5, 20.0)]


def _store(arrays, prefix, obj):
    """Every array, number, string and list of ``obj`` (a dataclass, dict or value) under ``prefix``."""
    if isinstance(obj, np.ndarray):
        if obj.dtype != object:
            arrays[prefix] = obj
        else:
            _store(arrays, prefix, obj.tolist())
    elif isinstance(obj, (bool, int, float, np.number, np.bool_)):
        arrays[prefix] = np.asarray(obj)
    elif isinstance(obj, str):
        arrays[prefix] = np.asarray(obj)
    elif obj is None:
        arrays[prefix] = np.asarray("None")
    elif isinstance(obj, dict):
        arrays[prefix + ".keys"] = np.asarray(sorted(map(str, obj)) or [""])
        for k, v in obj.items():
            if not _timing(str(k)):
                _store(arrays, f"{prefix}.{k}", v)
    elif isinstance(obj, (list, tuple)):
        if all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in obj):
            arrays[prefix] = np.asarray(obj, dtype=float)
        else:
            arrays[prefix + ".len"] = np.asarray(len(obj))
            for i, v in enumerate(obj):
                _store(arrays, f"{prefix}[{i}]", v)
    elif hasattr(obj, "__dataclass_fields__"):
        for k in obj.__dataclass_fields__:
            if _timing(k):
                continue
            _store(arrays, f"{prefix}.{k}", getattr(obj, k))
    elif callable(obj):
        arrays[prefix] = np.asarray(f"callable {type(obj).__name__}")
    else:
        arrays[prefix] = np.asarray(repr(obj))


def _timing(name: str) -> bool:
    """A wall or CPU time (left out: it differs from run to run)."""
    return name.startswith(("wall", "cpu")) or name.endswith(("wall_time_s", "cpu_time_s", "wall_s", "cpu_s",
                                                               "_ms"))


def _untimed(message: str) -> str:
    """The message without the wall time of the solve (" tried in 0.12 s")."""
    return re.sub(r" in \d+\.\d+ s", " in <t> s", message)


def _record(arrays, prefix, fn, *args, **kw):
    """Call ``fn`` and store its result, or the exception's type, message and attributes."""
    print(prefix, file=sys.stderr, flush=True)
    try:
        res = fn(*args, **kw)
    except ValueError as exc:
        arrays[prefix + ".error"] = np.asarray(type(exc).__name__)
        arrays[prefix + ".message"] = np.asarray(_untimed(str(exc)))
        attrs = {k: v for k, v in vars(exc).items()}
        _store(arrays, prefix + ".attrs", attrs)
        return None
    _store(arrays, prefix, res)
    return res


def _steady(arrays, ehl):
    solve = ehl.solve_line_contact
    for M, L in STEADY_ML:
        for visc in ("roelands", "barus"):
            _record(arrays, f"steady.moes_M{M:g}_L{L:g}_{visc}", solve, M=M, L=L, viscosity=visc)
    # the piezoviscous corner plan (Barus, PIEZO_CORNER_PLAN)
    for M, L in ((1000.0, 18.0), (500.0, 20.0), (600.0, 20.0)):
        _record(arrays, f"steady.corner_M{M:g}_L{L:g}", solve, M=M, L=L, viscosity="barus", compressible=False)
    for w, u in DIM_LOADS_SPEEDS:
        _record(arrays, f"steady.dim_w{w:g}_u{u:g}", solve, w_N_per_m=w, u_m_s=u, **DIM)
    prev = _record(arrays, "steady.warm_prev", solve, w_N_per_m=2.0e5, u_m_s=2.0, **DIM)
    _record(arrays, "steady.warm", solve, w_N_per_m=2.1e5, u_m_s=2.0, initial=prev, **DIM)
    _record(arrays, "steady.warm_rough", solve, w_N_per_m=2.1e5, u_m_s=2.0, initial=prev,
            roughness_m=lambda x: 0.02e-6 * np.cos(2 * np.pi * x / 1e-4), **DIM)
    _record(arrays, "steady.fmg_stop", solve, M=20.0, L=10.0, n_nodes=1025, fmg_cycles=1,
            stop_at_discretisation=0.1)
    _record(arrays, "steady.fmg", solve, M=20.0, L=10.0, n_nodes=513, fmg_cycles=1)
    _record(arrays, "steady.tight", solve, M=100.0, L=10.0, n_nodes=513, tol_pressure=1e-8,
            tol_residual=1e-8, tol_film=1e-6)
    _record(arrays, "steady.options", solve, M=20.0, L=5.0, gamma="F", switch=0.3, nu1=2, nu2=1,
            omega_gs=0.6, omega_j=0.5, load_mode=1, c_h0=0.1, stick=10.0)
    _record(arrays, "steady.coarse_user", solve, M=50.0, L=10.0, n_nodes=513, n_coarse=16, x_in=-4.0, x_out=1.4)
    rough = lambda x: 2e-8 * np.cos(2 * np.pi * x / 2e-4)
    _record(arrays, "steady.rough", solve, M=20.0, L=10.0, roughness_m=rough)
    _record(arrays, "steady.rough_ramp", solve, M=20.0, L=10.0, roughness_m=rough, roughness_ramp=(0.5, 1.0))
    _record(arrays, "steady.rough_no_newton", solve, M=20.0, L=10.0, roughness_m=rough, newton_after_cycles=0)
    _record(arrays, "steady.rough_pairs", solve, M=50.0, L=10.0, roughness_min_wavelength_dX=4.0,
            roughness_m=[lambda x: 1e-8 * np.sin(2 * np.pi * x / 1e-4), (np.linspace(-1e-3, 1e-3, 51),
                                                                         1e-8 * np.cos(np.linspace(0, 9, 51)))])
    _record(arrays, "steady.rough_dim", solve, w_N_per_m=3e5, u_m_s=2.0,
            roughness_m=lambda x: 0.05e-6 * np.cos(2 * np.pi * x / 5e-5), **DIM)
    # failure paths
    _record(arrays, "steady.collapse", solve, R_m=0.02, E_Pa=2.26e11, w_N_per_m=3.0e5, u_m_s=2.0, eta0_Pas=0.01,
            alpha_Pa_inv=2.2e-8, roughness_m=lambda x: 1.5e-6 * np.cos(2 * np.pi * x / 1e-4), max_cycles=30)
    _record(arrays, "steady.stall_max_cycles", solve, M=20.000000001, L=10.0, viscosity="barus",
            compressible=False, n_nodes=513, max_cycles=2, tol_residual=1e-12)
    _record(arrays, "steady.stall_dim", solve, max_cycles=2, tol_residual=1e-12, w_N_per_m=2e5, u_m_s=5.0,
            **DIM)
    _record(arrays, "steady.stall_options", solve, M=100.0, L=10.0, max_cycles=2, switch=3.0)
    _record(arrays, "steady.fail_fast_rule1", solve, M=10.0, L=40.0, viscosity="barus", compressible=False,
            newton_after_cycles=0)
    _record(arrays, "steady.fail_fast_rule2", solve, M=200.0, L=40.0, viscosity="barus", compressible=False,
            newton_after_cycles=0)
    _record(arrays, "steady.coupled_newton", solve, M=5.5, L=22.0, viscosity="barus", compressible=False)
    for name, kw in (("M_only", dict(M=10.0)), ("negative_R", dict(DIM, R_m=-1.0, w_N_per_m=1e5, u_m_s=1.0)),
                     ("low_eta", dict(DIM, eta0_Pas=1e-6, w_N_per_m=1e5, u_m_s=1.0)),
                     ("bad_grid", dict(M=10.0, L=5.0, n_nodes=1000)),
                     ("bad_ramp", dict(M=10.0, L=5.0, roughness_ramp=(0.5,))),
                     ("bad_viscosity", dict(M=10.0, L=5.0, viscosity="ree-eyring")),
                     ("bad_domain", dict(M=10.0, L=5.0, x_in=-0.5)),
                     ("bad_stop", dict(M=10.0, L=5.0, stop_at_discretisation=0.1)),
                     ("bad_initial", dict(M=10.0, L=5.0, initial="previous")),
                     ("bad_newton", dict(M=10.0, L=5.0, newton_after_cycles=-1)),
                     ("bad_solver", dict(M=10.0, L=5.0, solver="python")),
                     ("bad_wavelength", dict(M=10.0, L=5.0, roughness_m=lambda x: 0 * x,
                                             roughness_min_wavelength_dX=-1))):
        _record(arrays, f"steady.input_{name}", solve, **kw)


def _transient(arrays, ehl):
    solve = ehl.solve_line_contact_transient
    sm = ehl.solve_line_contact(M=20.0, L=10.0, n_nodes=257)
    wav = ehl.HarmonicWaviness(amplitude_m=0.1 * sm.h_central_m, wavelength_m=0.5 * sm.b_m)
    _record(arrays, "transient.characteristic", solve, M=20.0, L=10.0, n_nodes=257, roughness=wav, srr=0.5,
            n_steps=20)
    _record(arrays, "transient.bdf2", solve, M=20.0, L=10.0, n_nodes=129, roughness=wav, srr=-0.4,
            dT=0.03, n_steps=12)
    _record(arrays, "transient.bdf1", solve, M=20.0, L=10.0, n_nodes=129, roughness=wav, scheme="bdf1",
            dT=0.05, n_steps=8, extrapolate=False)
    _record(arrays, "transient.smooth_start", solve, M=20.0, L=10.0, n_nodes=129, roughness=wav,
            start="smooth", ramp_T=0.5, n_steps=15, speed_ratios=(1.2, 0.8))
    _record(arrays, "transient.rescue_always", solve, M=20.0, L=10.0, n_nodes=129, roughness=wav,
            substep_rescue="always", n_steps=5)
    _record(arrays, "transient.settings", solve, M=20.0, L=10.0, n_nodes=129, roughness=wav, n_steps=6,
            relaxation_settings=(dict(switch=0.3, nu1=2, nu2=1, omega_gs=0.6, omega_j=0.1, load_mode=1,
                                      c_h0=0.1, stick=10.0),))
    _record(arrays, "transient.pair", solve, M=20.0, L=10.0, n_nodes=129, n_steps=6,
            roughness=(lambda xi: 0.05 * sm.h_central_m * np.sin(2 * np.pi * xi / (0.4 * sm.b_m)), None))
    _record(arrays, "transient.smooth", solve, R_m=0.02, E_Pa=2.26e11, w_N_per_m=3e5, u_m_s=2.0,
            eta0_Pas=0.04, alpha_Pa_inv=2.2e-8, n_nodes=129, n_steps=4)
    _record(arrays, "transient.stall", solve, M=20.0, L=10.0, n_nodes=129, roughness=wav, n_steps=3,
            max_cycles_per_step=1, substep_rescue=False)
    _record(arrays, "transient.bad_scheme", solve, M=20.0, L=10.0, scheme="crank")
    _record(arrays, "transient.bad_field", solve, M=20.0, L=10.0, n_step=3)
    import gearfmu.ehl.transient as tr
    _record(arrays, "transient.amplitude_ratio", tr.waviness_amplitude_ratio, 20.0, 10.0, 0.5, n_nodes=129,
            periods_averaged=1)


def _scene_text(base: str, sections: dict) -> str:
    """``base`` (a scene's text) with the keys of ``sections`` ({"[mesh]": {"slices": 4}}) set;
    a section missing from ``base`` is appended."""
    out, cur = [], None
    pending = {s: dict(kv) for s, kv in sections.items()}
    for line in base.splitlines():
        head = line.strip()
        if head.startswith("["):
            if cur in pending:
                out += [f"{k} = {json.dumps(v)}" for k, v in pending.pop(cur).items()]
            cur = head
        elif cur in pending and "=" in head and not head.startswith("#"):
            key = head.split("=", 1)[0].strip()
            if key in pending[cur]:
                out.append(f"{key} = {json.dumps(pending[cur].pop(key))}")
                continue
        out.append(line)
    if cur in pending:
        out += [f"{k} = {json.dumps(v)}" for k, v in pending.pop(cur).items()]
    for s, kv in pending.items():
        out.append(s)
        out += [f"{k} = {json.dumps(v)}" for k, v in kv.items()]
    return "\n".join(out) + "\n"


SMALL = {"[tables]": {"points_per_mesh": 16, "torque_points": 1}}
TABLE_SCENES = {
    "default": {},
    "rough_ehl_level2": {"[mesh]": {"contact_model": "rough_ehl", "slices": 8},
                         "[roughness]": {"level": 2}, "[tables]": {"points_per_mesh": 32}},
    "smooth_ehl": {"[mesh]": {"contact_model": "smooth_ehl", "slices": 3}, **SMALL},
    "thermal_axis": {"[mesh]": {"slices": 8}, "[tables]": {"points_per_mesh": 32},
                     "[thermal]": {"standard_temperature_C": 30.0, "temperature_axis_C": [20.0, 60.0, 90.0]}},
    "thermal_state": {"[mesh]": {"slices": 8}, "[tables]": {"points_per_mesh": 32},
                      "[thermal]": {"pinion_temperature_C": 80.0, "gear_temperature_C": 65.0,
                                    "flank_law": "homogeneous"}},
    "oil_axis": {"[mesh]": {"contact_model": "smooth_ehl", "slices": 2}, **SMALL,
                 "[thermal]": {"temperature_axis_C": [40.0, 60.0, 80.0], "axis_quantity": "oil"}},
    "crowned_torques": {"[mesh]": {"slices": 6}, "[tables]": {"points_per_mesh": 16, "torque_points": 4},
                        "[operating]": {"torque_range_Nm": [500.0, 2500.0]},
                        "[deviations.pinion]": {"lead_crowning_um": 8.0}},
}


def _tables(arrays, checkout: Path):
    from gearfmu import stages
    from gearfmu.scene.reader import load_scene
    default = (checkout / "gearfmu" / "scene" / "data" / "default_scene.toml").read_text()
    with tempfile.TemporaryDirectory() as d:
        scenes = [(name, _scene_text(default, s)) for name, s in TABLE_SCENES.items()]
        scenes.append(("helical_seed001", (checkout / "examples" / "scenes" / "seed001_table1.toml").read_text()))
        for name, text in scenes:
            p = Path(d) / f"{name}.toml"
            p.write_text(text)
            scene = load_scene(p)
            _record(arrays, f"tables.{name}", lambda: _arrays_of(
                stages.compute_tables(scene, allow_large=True, cache=False)))


def _arrays_of(tables):
    out = {k: v for k, v in vars(tables).items() if k != "provenance"}
    prov = dict(tables.provenance)
    prov.pop("created_utc", None)
    pre = dict(prov.get("precompute", {}))
    pre.pop("wall_s", None)
    prov["precompute"] = pre
    out["provenance"] = json.dumps(_no_times(prov), sort_keys=True, default=str)
    return out


def _no_times(obj):
    if isinstance(obj, dict):
        return {k: _no_times(v) for k, v in obj.items() if not re.search(r"(wall|cpu|_s$|seconds)", str(k))}
    if isinstance(obj, list):
        return [_no_times(v) for v in obj]
    return obj


def _direct(arrays, checkout: Path):
    import dataclasses
    from gearfmu.assembly.direct_tvms import TransientFilmSettings, direct_mesh_stiffness
    from gearfmu.contact.models import RoughnessSpec
    from gearfmu.gear.geometry import pair_geometry
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.scene.reader import load_scene
    sc = load_scene(checkout / "examples" / "scenes" / "seed000_table1.toml")
    sc = dataclasses.replace(sc, mesh=dataclasses.replace(sc.mesh, slices=2))
    g = pair_geometry(sc.pair)
    s = np.array([g.s_pitch_m, g.s_start_m + 0.5 * (g.contact_ratio - 1.0) * g.base_pitch_m])
    st = TransientFilmSettings(n_nodes=65, T_average=2.0)
    for model, level, kw in (("hertz", None, {}), ("smooth_ehl", None, {}),
                             ("rough_steady", 1, {}), ("smooth_transient", None, {}),
                             ("rough_transient", 1, {}),
                             ("rough_steady", 4, {"check_film_parameter": True}),
                             ("hertz", None, {"e_pair_m": np.full((2, 2), 1e-6), "crowning_m": np.array([0.0, 2e-6])}),
                             ("smooth_ehl", None, {"torque_Nm": -1.0})):
        env = environment_from_scene(sc, roughness=RoughnessSpec.from_level(level) if level else None,
                                     max_workers=1)
        kw = dict(kw)
        T = kw.pop("torque_Nm", 2000.0)
        if "e_pair_m" in kw and "loading" in inspect.signature(direct_mesh_stiffness).parameters:
            from gearfmu.assembly.direct_tvms import PairLoading      # the errors as one argument
            kw["loading"] = PairLoading(kw.pop("e_pair_m"), kw.pop("crowning_m"))
        _record(arrays, f"direct.{model}_{level}_{len(arrays)}", direct_mesh_stiffness, env, sc.mesh, s, T, model,
                transient=st, max_workers=1, **kw)


def _synthetic(arrays):
    from gearfmu.tables.synthetic import rectangular_wave_tables, tables_from_arrays
    rng = np.random.default_rng(7)
    k = np.abs(rng.normal(3e8, 5e7, size=(2, 64)))
    k[1, 40:] = 0.0
    e = rng.normal(0.0, 2e-6, size=(2, 64))
    _record(arrays, "synthetic.plain", tables_from_arrays, k_N_per_m=k)
    _record(arrays, "synthetic.positional", tables_from_arrays, None, 2 * math.pi / 30, k, e, 1e-5, 0.05, 0.07,
            0.01, 0.02, 30, 42)
    _record(arrays, "synthetic.torque_axis", tables_from_arrays, k_N_per_m=np.stack([k, 1.1 * k]), e_m=e,
            backlash_half_m=np.full(64, 2e-5), torque_Nm=[10.0, 100.0], contact_ratio=1.6,
            static_te_m=np.zeros((2, 64)), provenance={"source": "test"})
    zone = (np.arange(64)[None, :] - 32 * np.arange(2)[:, None]) % 64 < 1.6 * 32     # 32 points per mesh
    _record(arrays, "synthetic.engagement", tables_from_arrays, mesh_period_rad=2 * math.pi / 50,
            k_N_per_m=np.where(zone, k, 0.0), e_m=e, engagement_in_rad=0.0, engagement_out_rad=1.6 * 2 * math.pi / 50)
    _record(arrays, "synthetic.k_mean", tables_from_arrays, k_N_per_m=k, k_mean_N_per_m=4e8,
            e_comprehensive_m=np.zeros(64))
    _record(arrays, "synthetic.bad_shape", tables_from_arrays, k_N_per_m=k, e_m=e[:, :10])
    _record(arrays, "synthetic.bad_teeth", tables_from_arrays, k_N_per_m=k, teeth_pinion=0)
    _record(arrays, "synthetic.rect", rectangular_wave_tables, 3e8, contact_ratio=1.55, backlash_half_m=1e-5,
            pair_error_m=lambda slot, u: 1e-6 * u, zone_edges=True, teeth_pinion=23, inertia_gear_kgm2=0.5)
    _record(arrays, "synthetic.rect_default", rectangular_wave_tables, 2e8)


def _gearbox(arrays, checkout: Path):
    from gearfmu.gearbox.cases import gearbox_case
    from gearfmu.gearbox.reference import simulate_reference
    for case in ("contact_loss", "torque_step"):
        model, kw = gearbox_case(case, mesh_periods=6)
        _record(arrays, f"gearbox.{case}", simulate_reference, model, **kw)
    model, kw = gearbox_case("intermediate_shaft_resonance", mesh_periods=4)
    _record(arrays, "gearbox.resonance_rk45", simulate_reference, model, **kw, method="RK45", rtol=1e-8,
            atol_scale=10.0, steps_per_period=32.0)
    try:
        from gearfmu import drivetrain          # the drivetrain orchestration (older trees)
    except ImportError:
        from gearfmu import stages as drivetrain
    scene = drivetrain.load_any(checkout / "examples" / "scenes" / "gearbox_two_stage.toml")[1]
    tables = drivetrain.stage_tables(scene, allow_large=True)
    model = drivetrain.gearbox_model(scene, tables)
    w = scene.motor.speed_rad_s
    period = 2 * math.pi / w / model.meshes[0].tables.teeth_pinion
    _record(arrays, "gearbox.two_stage", simulate_reference, model, stop_time_s=8 * period,
            comm_step_s=period / 4, motor_torque_Nm=scene.motor.torque_Nm, motor_speed_start_rad_s=w)


def run(checkout: Path, out: Path, only) -> int:
    sys.path.insert(0, str(checkout))
    import gearfmu
    import gearfmu.ehl as ehl
    assert Path(gearfmu.__file__).resolve().is_relative_to(checkout.resolve()), gearfmu.__file__
    arrays = {}
    for group in only:
        if group == "steady":
            _steady(arrays, ehl)
        elif group == "transient":
            _transient(arrays, ehl)
        elif group == "tables":
            _tables(arrays, checkout)
        elif group == "direct":
            _direct(arrays, checkout)
        elif group == "synthetic":
            _synthetic(arrays)
        elif group == "gearbox":
            _gearbox(arrays, checkout)
    np.savez(out, **arrays)
    print(json.dumps({"gearfmu": gearfmu.__file__, "arrays": len(arrays), "file": str(out)}))
    return 0


def diff(a_path: Path, b_path: Path) -> int:
    a, b = np.load(a_path, allow_pickle=False), np.load(b_path, allow_pickle=False)
    bad = []
    for k in sorted(set(a.files) | set(b.files)):
        if k not in a.files or k not in b.files:
            bad.append(f"{k}: only in {'A' if k in a.files else 'B'}")
            continue
        x, y = a[k], b[k]
        if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
            d = ""
            if x.shape == y.shape and x.dtype.kind == "f" and y.dtype.kind == "f":
                with np.errstate(invalid="ignore"):
                    d = f" max|A-B| = {float(np.nanmax(np.abs(x - y))) if x.size else 0.0:.3g}"
            elif x.dtype.kind == "U":
                d = f" A={str(x)[:200]!r} B={str(y)[:200]!r}"
            bad.append(f"{k}: differs{d}")
    groups = sorted({k.split(".")[0] for k in a.files})
    print(json.dumps({"compared": len(set(a.files) | set(b.files)), "groups": groups,
                      "different": len(bad), "bit_identical": not bad}))
    for line in bad:
        print(line)
    return 0 if not bad else 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("checkout", type=Path)
    r.add_argument("out", type=Path)
    r.add_argument("--only", default=",".join(GROUPS), help="comma-separated groups: " + ", ".join(GROUPS))
    d = sub.add_parser("diff")
    d.add_argument("a", type=Path)
    d.add_argument("b", type=Path)
    args = ap.parse_args(argv)
    if args.cmd == "run":
        only = args.only.split(",")
        bad = [g for g in only if g not in GROUPS]
        if bad:
            ap.error(f"--only: unknown group {bad[0]!r} (one of {', '.join(GROUPS)})")
        return run(args.checkout, args.out, only)
    return diff(args.a, args.b)


if __name__ == "__main__":
    sys.exit(main())
