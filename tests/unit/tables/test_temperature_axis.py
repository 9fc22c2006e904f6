"""Temperature axis of the tables (format version 2) and the FMU input
``bulk_temperature`` (docs/tables.md "Operating axes", docs/model.md
"Temperature axis", docs/fmu.md).

References, none produced by gearfmu:
* the stored slices themselves: at an axis node every kernel must reproduce the
  single-temperature tables bit for bit (docs/model.md: one slice at a node);
* between nodes the trilinear interpolation in (temperature, pinion angle,
  torque) written out by hand as the weighted sum of the 8 corner values
  (a formula independent of the kernels' nested arithmetic), to 1e-12;
* native (numba), pythonfmu FMU and standalone FMU: three implementations of the
  same rule, compared with each other under a temperature ramp (<= 1e-9 of
  range, the project's agreement criterion; docs/standalone.md);
* seed 004 Fig. 5 ("low-high-low"): the mesh stiffness is highest at the
  standard temperature 30 degC and lower at 70 degC (expansion) and lower
  still at 10 degC (shrinkage; seed 004 Tables 2-3: the 10 degC shrinkage lowers
  every stiffness more than the 70 degC expansion) -- checked on the mean
  mesh_stiffness output of dynamic runs;
* the FMI 2.0 standard for the interface: fmi2Discard and a log message for a
  rejected step, the value restored by fmi2SetFMUstate.
"""
import json
import math
from pathlib import Path

import fmpy
from fmpy.fmi1 import FMICallException
import numpy as np
import pytest

from gearfmu.common.vocabulary import INTEGRATORS
from gearfmu.fmu.compare import native_columns, output_names
from gearfmu.fmu.pythonfmu_build import build_fmu, compile_kernel
from gearfmu.fmu.runtime.kernel_api import load_kernel
from gearfmu.fmu.modeldesc import expand_variables, load_spec
from gearfmu.dynamics.native import NativeInputError, simulate
from gearfmu.pipeline import compute_tables
from gearfmu.scene.reader import load_scene
from gearfmu.ssp import build_ssp, default_variants
from gearfmu.fmu.standalone_build import build_standalone_fmu
from gearfmu.tables.mesh_tables import TableError, TemperatureRangeError, load_tables

from factories import AXIS, make_tables, temp_tables
from support.fmpy_host import Inst as _Inst, callbacks

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

H = 1e-4
N_STEPS = 80
REPO = Path(__file__).resolve().parents[3]


class Inst(_Inst):
    """support.fmpy_host.Inst with a logger that formats the C runtime's printf-style messages."""

    def __init__(self, path, name):
        from fmpy.fmi2 import FMU2Slave
        self.md = fmpy.read_model_description(str(path))
        self.log = []
        self._cb = callbacks(self.log)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=fmpy.extract(str(path)),
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.fmu.instantiate(callbacks=self._cb, loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()


@pytest.fixture(scope="module")
def tabs():
    return temp_tables()


@pytest.fixture(scope="module")
def fmus(tabs, tmp_path_factory):
    d = tmp_path_factory.mktemp("tempaxis")
    tt, _ = tabs
    kw = dict(max_step_s=1e-5, pinion_torque_start_Nm=100.0, pinion_speed_start_rad_s=100.0,
              stop_time_s=N_STEPS * H, output_interval_s=H)
    return {"pythonfmu": build_fmu(tt, d / "py.fmu", model_name="tempPy", **kw),
            "standalone": build_standalone_fmu(tt, d / "sa.fmu", model_name="tempSa", validation=False, **kw),
            "plain": build_fmu(make_tables(), d / "plain.fmu", model_name="plain", **kw)}


# ------------------------------------------------------------------ format
def test_tables_with_temperature_axis_round_trip_as_version_2(tabs, tmp_path):
    tt, _ = tabs
    for back in (load_tables(tt.save(tmp_path / "t.gtab")), load_tables(tt.write_dir(tmp_path / "d"))):
        assert back.has_temperature_axis and back.temperature_C.tolist() == list(AXIS)
        assert back.temperature_reference_C == 30.0
        for n in ("k_N_per_m", "e_m", "backlash_half_m", "torque_Nm", "e_comprehensive_m", "static_te_m"):
            a, b = getattr(back, n), getattr(tt, n)
            assert (a is None and b is None) or np.array_equal(a, b), n
    meta = json.loads((tmp_path / "d" / "tables.json").read_text())
    assert meta["version"] == 2 and meta["n_temperature"] == 3
    assert [a["name"] for a in meta["axes"]] == ["torque_Nm", "temperature_C"]
    assert meta["arrays"]["k_N_per_m"]["shape"] == [2, 3, 2, 64]
    # tables without the axis are still written as version 1 and read with NTemp = 1
    plain = make_tables()
    assert json.loads(plain.to_bytes()[0])["version"] == 1
    back = load_tables(plain.save(tmp_path / "p.gtab"))
    assert not back.has_temperature_axis and back.n_temperature == 1


def test_version_2_with_an_unknown_operating_axis_is_rejected(tabs, tmp_path):
    tt, _ = tabs
    meta, binary = tt.to_bytes()
    m = json.loads(meta)
    m["axes"][1]["name"] = "speed_rad_s"
    d = tmp_path / "t"
    d.mkdir()
    (d / "tables.json").write_text(json.dumps(m))
    (d / "tables.bin").write_bytes(binary)
    with pytest.raises(TableError, match="operating axis 'speed_rad_s' unknown"):
        load_tables(d)


# -------------------------------------------------------------- the C kernel
@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    return load_kernel(compile_kernel(tmp_path_factory.mktemp("k")))


class Kernel:
    def __init__(self, L, t):
        self.L, self.t = L, t
        self.arrs = [np.ascontiguousarray(a, dtype=float) for a in
                     (t.torque_Nm, t.k_N_per_m, t.e_m, t.backlash_half_m)]
        self.m = np.zeros(L.gk_sizeof_model() // 8 + 2)
        self.s = np.zeros(4)
        self.out = np.zeros(L.gk_n_outputs(t.slots))
        assert L.gk_init(self.m.ctypes.data, t.slots, t.n_phi, t.n_torque, *[a.ctypes.data for a in self.arrs],
                         t.phi_period_rad, t.base_radius_pinion_m, t.base_radius_gear_m, t.inertia_pinion_kgm2,
                         t.inertia_gear_kgm2, t.k_mean_N_per_m) == 0
        assert L.gk_set_damping(self.m.ctypes.data, 0.02, 0) == 0
        if t.has_temperature_axis:
            self.tax = np.ascontiguousarray(t.temperature_C)
            assert L.gk_set_temperature_axis(self.m.ctypes.data, self.tax.size, self.tax.ctypes.data) == 0

    def temperature(self, T):
        return self.L.gk_set_temperature(self.m.ctypes.data, T)

    def run(self, T1, n=40):
        assert self.L.gk_initialize(self.m.ctypes.data, self.s.ctypes.data, 0.01, 100.0, T1) == 0
        rows = []
        for _ in range(n):
            assert self.L.gk_do_step(self.m.ctypes.data, self.s.ctypes.data, T1, T1 * 1.5, H, 1e-5,
                                     self.out.ctypes.data) == 0
            rows.append(self.out.copy())
        return np.array(rows)

    def stiffness_at(self, theta, T1):
        """mesh_stiffness with every slot pressed into contact (x far beyond e + b)."""
        self.s[:] = (theta, 0.0, 1e-3, 0.0)
        assert self.L.gk_outputs(self.m.ctypes.data, self.s.ctypes.data, T1, self.out.ctypes.data) == 0
        return self.out[6]


@pytest.mark.parametrize("T1", [100.0, 150.0])
def test_at_a_node_both_kernels_reproduce_the_single_temperature_tables_exactly(tabs, lib, T1):
    tt, slices = tabs
    for T, sl in zip(AXIS, slices):
        k = Kernel(lib, tt)
        assert k.temperature(T) == 0
        ref = Kernel(lib, sl).run(T1)
        assert np.array_equal(k.run(T1), ref), T
        for ig in ("rk4", "rk4_kink", "rk4_node"):
            kw = dict(stop_time_s=20 * H, comm_step_s=H, max_step_s=1e-5, pinion_torque_Nm=T1,
                      pinion_speed_start_rad_s=100.0, damping_ratio=0.02, integrator=ig)
            a = simulate(tt, bulk_temperature_C=T, **kw)
            b = simulate(sl, **kw)
            assert np.array_equal(a.dte, b.dte) and np.array_equal(a.pair_force, b.pair_force), (T, ig)


def test_between_nodes_the_trilinear_rule_by_hand(tabs, lib):
    """k at (T, theta1, T1) = sum over the 8 corners of w_T w_phi w_Tq k[corner]
    (docs/model.md "Temperature axis"), by hand; the C kernel and
    tables.at_temperature (the native path) to 1e-12, and bitwise to each other."""
    tt, _ = tabs
    kern = Kernel(lib, tt)
    dphi = tt.phi_period_rad / tt.n_phi
    rng = np.random.default_rng(4)
    for _ in range(25):
        T = rng.uniform(10.0, 70.0)
        T1 = rng.uniform(50.0, 150.0)
        theta = rng.uniform(0.0, tt.phi_period_rad)
        a = 0 if T < 30.0 else 1
        wT = (T - AXIS[a]) / (AXIS[a + 1] - AXIS[a])
        wq = (T1 - 50.0) / 100.0
        s = theta / dphi
        i0 = int(math.floor(s))
        wp = s - i0
        i1 = (i0 + 1) % tt.n_phi
        hand = 0.0
        for ia, fa in ((a, 1 - wT), (a + 1, wT)):
            for ip, fp in ((i0, 1 - wp), (i1, wp)):
                for iq, fq in ((0, 1 - wq), (1, wq)):
                    hand += fa * fp * fq * tt.k_N_per_m[iq, ia, :, ip].sum()
        assert kern.temperature(T) == 0
        c_val = kern.stiffness_at(theta, T1)
        ref_tab = tt.at_temperature(T)
        py_val = Kernel(lib, ref_tab).stiffness_at(theta, T1)
        assert c_val == pytest.approx(hand, rel=1e-12)
        assert c_val == py_val  # node-wise blend first: the same arithmetic in both paths


def test_kernel_rejects_temperatures_outside_the_axis_and_nan(tabs, lib):
    tt, _ = tabs
    k = Kernel(lib, tt)
    assert k.temperature(30.0) == 0
    for bad in (9.999, 70.001, float("nan"), float("inf")):
        assert k.temperature(bad) == 2  # GK_ERR_INPUT
    assert k.temperature(10.0) == 0 and k.temperature(70.0) == 0


def test_native_rejects_out_of_range_and_missing_axis(tabs):
    tt, slices = tabs
    kw = dict(stop_time_s=5 * H, comm_step_s=H, max_step_s=1e-5, pinion_torque_Nm=100.0,
              pinion_speed_start_rad_s=100.0, damping_ratio=0.02)
    with pytest.raises(NativeInputError, match=r"80.0 degC outside the table range \[10.0, 70.0\]"):
        simulate(tt, bulk_temperature_C=80.0, **kw)
    with pytest.raises(NativeInputError, match="bulk_temperature_C: contains NaN"):
        simulate(tt, bulk_temperature_C=[30.0, float("nan"), 30.0, 30.0, 30.0], **kw)
    with pytest.raises(NativeInputError, match="no temperature axis"):
        simulate(slices[0], bulk_temperature_C=30.0, **kw)
    with pytest.raises(TemperatureRangeError):
        tt.at_temperature(5.0)


# ------------------------------------------------------------- the FMUs
def _ramp():
    return np.linspace(12.0, 68.0, N_STEPS + 1)


@pytest.mark.parametrize("integrator", ["rk4", "rk4_kink", "rk4_node"])
def test_native_pythonfmu_standalone_agree_with_a_temperature_ramp(tabs, fmus, integrator):
    tt, _ = tabs
    temps = _ramp()
    ref = simulate(tt, stop_time_s=N_STEPS * H, comm_step_s=H, max_step_s=1e-5, pinion_torque_Nm=100.0,
                   pinion_speed_start_rad_s=100.0, damping_ratio=0.02, bulk_temperature_C=temps,
                   integrator=integrator)
    assert ref.info["temperature_runs"] == N_STEPS
    cols = native_columns(ref, tt.slots)
    sig = np.array([(i * H, temps[i]) for i in range(N_STEPS + 1)],
                   dtype=[("time", float), ("bulk_temperature", float)])
    for kind in ("pythonfmu", "standalone"):
        res = fmpy.simulate_fmu(str(fmus[kind]), stop_time=N_STEPS * H, output_interval=H, step_size=H,
                                input=sig, start_values={"integrator": INTEGRATORS[integrator]})
        for n in output_names(tt.slots):
            rngv = max(float(np.ptp(cols[n])), 1e-300)
            assert np.max(np.abs(res[n] - cols[n])) <= 1e-9 * rngv, (kind, n)
    # the temperature matters: a run at constant 30 degC differs by far more than that
    flat = simulate(tt, stop_time_s=N_STEPS * H, comm_step_s=H, max_step_s=1e-5, pinion_torque_Nm=100.0,
                    pinion_speed_start_rad_s=100.0, damping_ratio=0.02, bulk_temperature_C=30.0)
    assert np.max(np.abs(flat.dte - ref.dte)) > 1e-3 * np.ptp(ref.dte)


@pytest.mark.parametrize("kind", ["pythonfmu", "standalone"])
def test_out_of_range_or_nan_temperature_is_discarded_with_log_state_unchanged(fmus, kind):
    x = Inst(fmus[kind], "oor")
    for i in range(3):
        x.set(bulk_temperature=30.0)
        x.fmu.doStep(i * H, H)  # fmpy raises FMICallException on any status above warning
    before = x.out()
    for bad in (75.0, 5.0, float("nan")):
        x.set(bulk_temperature=bad)
        with pytest.raises(FMICallException) as info:
            x.fmu.doStep(3 * H, H)
        assert info.value.status == 2  # fmi2Discard
        assert np.array_equal(x.out(), before)  # the step was not taken
    x.set(bulk_temperature=70.0)
    x.fmu.doStep(3 * H, H)  # the upper end itself is inside
    x.close()
    msgs = [m for st, m in x.log if st == 2]
    assert any("bulk_temperature = 75" in m and "outside the table range [10" in m and "70" in m for m in msgs), msgs
    assert any("bulk_temperature = 5" in m and "outside the table range" in m for m in msgs), msgs
    assert any("bulk_temperature = nan" in m.lower() for m in msgs), msgs


@pytest.mark.parametrize("kind", ["pythonfmu", "standalone"])
def test_fmu_state_restores_the_temperature_input(fmus, kind):
    x = Inst(fmus[kind], "st")
    for i in range(5):
        x.set(bulk_temperature=20.0 + i)
        x.fmu.doStep(i * H, H)
    saved = x.fmu.getFMUstate()
    serial = x.fmu.serializeFMUstate(saved)
    rows_a = []
    for i in range(5, 15):
        x.fmu.doStep(i * H, H)  # the input keeps its last value, 24 degC
        rows_a.append(x.out())
    x.set(bulk_temperature=60.0)
    x.fmu.doStep(15 * H, H)
    restored = x.fmu.deSerializeFMUstate(serial)
    x.fmu.setFMUstate(restored)
    vr = x.vr["bulk_temperature"]
    assert x.fmu.getReal([vr]) == [24.0]
    rows_b = []
    for i in range(5, 15):
        x.fmu.doStep(i * H, H)
        rows_b.append(x.out())
    x.fmu.freeFMUstate(saved)
    x.fmu.freeFMUstate(restored)
    x.close()
    assert np.array_equal(np.array(rows_a), np.array(rows_b))


def test_interface_has_the_input_only_with_a_temperature_axis(fmus, tabs):
    tt, _ = tabs
    md = fmpy.read_model_description(str(fmus["pythonfmu"]))
    v = {x.name: x for x in md.modelVariables}
    bt = v["bulk_temperature"]
    assert (bt.causality, bt.variability, bt.unit) == ("input", "continuous", "degC")
    assert (float(bt.start), float(bt.min), float(bt.max)) == (30.0, 10.0, 70.0)
    assert max(x.valueReference for x in md.modelVariables) == bt.valueReference  # listed last
    unit = {u.name: u for u in md.unitDefinitions}["degC"]
    assert unit.baseUnit.K == 1 and unit.baseUnit.offset == 273.15  # FMI 2.0 BaseUnit of degC
    sa = {x.name for x in fmpy.read_model_description(str(fmus["standalone"])).modelVariables}
    assert "bulk_temperature" in sa
    plain = {x.name: x.valueReference for x in fmpy.read_model_description(str(fmus["plain"])).modelVariables}
    assert "bulk_temperature" not in plain
    assert all(plain[n] == v[n].valueReference for n in plain)  # other value references unchanged
    spec = load_spec()
    assert len(expand_variables(spec, 2, ("temperature_axis",))) == len(expand_variables(spec, 2)) + 1


def test_ssp_temperature_variants(fmus, tmp_path):
    var = default_variants(0.02, (10.0, 70.0))
    assert var["temperature_low"]["bulk_temperature"] == 10.0 and var["temperature_high"]["bulk_temperature"] == 70.0
    assert "temperature_low" not in default_variants(0.02)
    import zipfile
    p = build_ssp(fmus["pythonfmu"], tmp_path / "t.ssp", var, stop_time_s=N_STEPS * H)
    with zipfile.ZipFile(p) as z:
        ssv = z.read("resources/temperature_high.ssv").decode()
        ssd = z.read("temperature_high.ssd").decode()
    # the variant's set gives the input its start value by the FMU's name, bound on the component
    assert '<ssv:Parameter name="bulk_temperature"><ssv:Real value="70.0" unit="degC" />' in ssv
    assert 'source="resources/temperature_high.ssv"' in ssd


# --------------------------------------------------- scene -> tables (seed 004)
SEED004_SCENE = (REPO / "examples" / "scenes" / "seed004_pair1.toml").read_text().replace(
    "slices = 25", "slices = 5")


@pytest.fixture(scope="module")
def seed004():
    plain = compute_tables(load_scene(SEED004_SCENE))
    hot = compute_tables(load_scene(SEED004_SCENE + "\n[thermal]\nstandard_temperature_C = 30.0\n"
                                                    "temperature_axis_C = [10.0, 30.0, 70.0]\n"))
    return plain, hot


def test_scene_temperature_axis_slice_at_standard_temperature_is_the_standard_table(seed004):
    plain, hot = seed004
    assert hot.temperature_C.tolist() == [10.0, 30.0, 70.0] and hot.default_temperature_C == 30.0
    at30 = hot.at_temperature(30.0)
    # seed 004 eq 27-28 at t = t0: no thermal compliance, the standard stiffness
    assert np.array_equal(at30.k_N_per_m, plain.k_N_per_m) and np.array_equal(at30.e_m, plain.e_m)
    assert np.array_equal(at30.static_te_m, plain.static_te_m)
    assert hot.provenance["thermal"]["flank_law"] == "radial_tangential"


def test_seed004_low_high_low_in_dynamic_runs(seed004):
    """Seed 004 Fig. 5: stiffness highest at the standard 30 degC; the 10 degC
    shrinkage lowers it more than the 70 degC expansion (Tables 2-3)."""
    _, hot = seed004
    w = 2000.0 * 2 * math.pi / 60
    period = 2 * math.pi / w  # one pinion revolution
    mean_k = {}
    for T in (10.0, 30.0, 70.0):
        r = simulate(hot, stop_time_s=round(period / 2e-5) * 2e-5, comm_step_s=2e-5, pinion_torque_Nm=381.97,
                     pinion_speed_start_rad_s=w, damping_ratio=0.05, bulk_temperature_C=T)
        assert "diverged_at_step" not in r.info
        mean_k[T] = float(np.mean(r.mesh_stiffness[len(r.mesh_stiffness) // 4:]))
    assert mean_k[30.0] > mean_k[70.0] > mean_k[10.0], mean_k


# ------------------------------------------- oil temperature axis (eta0 of the EHL film)
# Tiny smooth_ehl scene: seed 004 pair I with its Table 4 oil (SCH632, 320 / 38.5 cSt at 40 / 100 degC),
# here at 40 degC, one face slice, 8 points per mesh period, two torque rows, in-process film solves.
OIL_AXIS = (40.0, 80.0)
OIL_TEXT = ((REPO / "examples" / "scenes" / "seed004_pair1.toml").read_text()
            .replace('contact_model = "hertz"', 'contact_model = "smooth_ehl"').replace("slices = 25", "slices = 1")
            .replace("points_per_mesh = 64", "points_per_mesh = 8\ntorque_points = 2")
            .replace("torque_Nm = 381.97", "torque_Nm = 381.97\ntorque_range_Nm = [381.97, 450.0]")
            .replace("temperature_C = 60.0", "temperature_C = 40.0"))


def _oil_tables(text):
    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.assembly.precompute import precompute_tables

    sc = load_scene(text)
    return sc, precompute_tables(sc.pair, sc.mesh, points_per_mesh=sc.tables.points_per_mesh,
                                 nominal_torque_Nm=sc.operating.torque_Nm,
                                 contact_env=environment_from_scene(sc, max_workers=1), thermal=sc.thermal)


@pytest.fixture(scope="module")
def oil():
    # alpha held at the [lubricant] value along the axis (oil_alpha = "constant"), so that the
    # 80 degC slice can be compared bit for bit with the scene written at 80 degC; the default
    # (Roelands alpha(T)) has its own test below
    sc, tab = _oil_tables(OIL_TEXT + f"\n[thermal]\naxis_quantity = \"oil\"\noil_alpha = \"constant\"\n"
                                     f"temperature_axis_C = {list(OIL_AXIS)}\n")
    # the table built at one oil temperature (no axis): the scene's [lubricant] temperature_C = 80
    _, single80 = _oil_tables(OIL_TEXT.replace("temperature_C = 40.0", "temperature_C = 80.0"))
    return sc, tab, single80


def test_oil_axis_film_thickness_follows_dowson_higginson_and_moes(oil):
    """The oil axis changes eta0 by Walther / ASTM D341 (solved here with numpy, independent of
    gearfmu) and the film with it: h_min(40)/h_min(80) at the pitch point against Dowson &
    Higginson (1966) h_min ~ U^0.70 = (eta0 ratio)^0.70, and h_c against Moes (1992), both fits,
    within 3 %; h_min itself within 15 % of Dowson-Higginson (seed 000 test tolerance)."""
    import dataclasses

    from gearfmu.scene.physics import environment_from_scene
    from gearfmu.ehl.fits import dowson_higginson_min_film, moes_central_film, moes_parameters
    from gearfmu.ehl.mesh_film import contact_kinematics, solve_slice_film
    from gearfmu.gear.geometry import pair_geometry

    sc, tab, _ = oil
    eta = tab.provenance["thermal"]["oil"]["eta0_Pas"]
    M = np.array([[1.0, -math.log10(313.15)], [1.0, -math.log10(373.15)]])
    A, B = np.linalg.solve(M, [math.log10(math.log10(320.7)), math.log10(math.log10(39.2))])
    for t, e in zip(OIL_AXIS, eta):
        assert e == pytest.approx(870.0e-6 * (10 ** (10 ** (A - B * math.log10(t + 273.15))) - 0.7), rel=1e-10)
    g = pair_geometry(sc.pair)
    env = environment_from_scene(sc, max_workers=1)
    R, u, _ = (float(x) for x in contact_kinematics(g, g.s_pitch_m, env.omega1_rad_s))
    w = sc.operating.torque_Nm / g.rb1_m / sc.pair.pinion.face_width_m
    h_min, h_c, dh, moes = [], [], [], []
    for e in eta:
        fe = dataclasses.replace(env, eta0_Pas=e).film_environment()
        out = solve_slice_film(fe, R, u, w)
        assert out.status == "ok"
        E = fe.E_prime_Pa
        W, U, G = w / (E * R), e * u / (E * R), fe.alpha_Pa_inv * E
        h_min.append(out.h_min_m)
        h_c.append(out.h_central_m)
        dh.append(R * dowson_higginson_min_film(W, U, G))
        moes.append(R * moes_central_film(*moes_parameters(W, U, G)) * math.sqrt(2 * U))
    assert h_min[1] < h_min[0] and h_c[1] < h_c[0]                      # hotter oil, thinner film
    assert h_min[0] / h_min[1] == pytest.approx((eta[0] / eta[1]) ** 0.70, rel=0.03)
    assert h_c[0] / h_c[1] == pytest.approx(moes[0] / moes[1], rel=0.03)
    assert h_min == pytest.approx(dh, rel=0.15)
    # thinner film, stiffer film (seed 000 eq 8: k_film = A B / h): the mesh stiffness rises with T
    k = tab.k_total_N_per_m().mean(axis=-1)                             # (NT, NTemp)
    assert np.all(k[:, 1] > k[:, 0])


def test_oil_axis_slice_is_the_table_built_at_that_oil_temperature(oil):
    """The slice at 80 degC equals, bit for bit, the whole table build of the scene whose
    lubricant is at 80 degC (an independent precompute run); the start value is the scene's
    oil temperature; the input is named oil_temperature everywhere."""
    sc, tab, single80 = oil
    at80 = tab.at_temperature(80.0)
    for n in ("k_N_per_m", "e_m", "static_te_m", "torque_Nm"):
        assert np.array_equal(getattr(at80, n), getattr(single80, n)), n
    assert tab.temperature_input == "oil_temperature" and tab.default_temperature_C == 40.0
    assert tab.provenance["thermal"]["axis_quantity"] == "oil"
    with pytest.raises(TemperatureRangeError, match=r"oil_temperature = 90.0 degC outside the table range \[40.0, 80.0\]"):
        tab.at_temperature(90.0)
    names = [v.name for v in expand_variables(load_spec(), tab.slots, ("oil_temperature_axis",))]
    assert "oil_temperature" in names and "bulk_temperature" not in names


@pytest.fixture(scope="module")
def oil_fmus(oil, tmp_path_factory):
    d = tmp_path_factory.mktemp("oilaxis")
    _, tab, _ = oil
    kw = dict(max_step_s=1e-5, pinion_torque_start_Nm=381.97, pinion_speed_start_rad_s=209.0,
              stop_time_s=N_STEPS * H, output_interval_s=H, damping_ratio=0.05)
    return {"pythonfmu": build_fmu(tab, d / "oil_py.fmu", model_name="oilPy", **kw),
            "standalone": build_standalone_fmu(tab, d / "oil_sa.fmu", model_name="oilSa", validation=False, **kw)}


@pytest.mark.parametrize("kind", ["pythonfmu", "standalone"])
def test_fmu_oil_temperature_input_matches_native_on_the_single_temperature_table(oil, oil_fmus, kind):
    """FMU (fmpy) with oil_temperature = 80 degC (an axis node) against the native solver on the
    table built at 80 degC alone (1e-9 of range, the project's agreement criterion).  Its
    k_mean (damping reference) is the axis tables' one, the scene's 40 degC (docs/thermal.md)."""
    import dataclasses

    _, tab, single80 = oil
    ref_tab = dataclasses.replace(single80, k_mean_N_per_m=tab.k_mean_N_per_m)
    ref = simulate(ref_tab, stop_time_s=N_STEPS * H, comm_step_s=H, max_step_s=1e-5, pinion_torque_Nm=381.97,
                   pinion_speed_start_rad_s=209.0, damping_ratio=0.05)
    cols = native_columns(ref, tab.slots)
    md = {v.name: v for v in fmpy.read_model_description(str(oil_fmus[kind])).modelVariables}
    assert "oil_temperature" in md and "bulk_temperature" not in md
    v = md["oil_temperature"]
    assert (v.causality, v.unit, float(v.start), float(v.min), float(v.max)) == ("input", "degC", 40.0, 40.0, 80.0)
    res = fmpy.simulate_fmu(str(oil_fmus[kind]), stop_time=N_STEPS * H, output_interval=H, step_size=H,
                            start_values={"oil_temperature": 80.0})
    for n in ("mesh_stiffness", "dte", "mesh_force"):
        rngv = max(float(np.ptp(cols[n])), 1e-300)
        assert np.max(np.abs(res[n] - cols[n])) <= 1e-9 * rngv, n
    # the oil temperature matters: at 40 degC the stiffness differs by far more than that
    cold = fmpy.simulate_fmu(str(oil_fmus[kind]), stop_time=N_STEPS * H, output_interval=H, step_size=H)
    assert np.max(np.abs(cold["mesh_stiffness"] - cols["mesh_stiffness"])) > 1e-4 * np.mean(cols["mesh_stiffness"])


@pytest.mark.parametrize("kind", ["pythonfmu", "standalone"])
def test_fmu_oil_temperature_out_of_range_is_discarded_with_a_log_naming_it(oil_fmus, kind):
    x = Inst(oil_fmus[kind], "oiloor")
    x.set(oil_temperature=50.0)
    x.fmu.doStep(0.0, H)
    before = x.out()
    for bad in (95.0, float("nan")):
        x.set(oil_temperature=bad)
        with pytest.raises(FMICallException) as info:
            x.fmu.doStep(H, H)
        assert info.value.status == 2  # fmi2Discard
        assert np.array_equal(x.out(), before)
    x.close()
    msgs = [m for st, m in x.log if st == 2]
    assert any("oil_temperature = 95" in m and "outside the table range [40" in m and "80" in m for m in msgs), msgs
    assert any("oil_temperature = nan" in m.lower() for m in msgs), msgs


def test_bulk_and_oil_axis_is_gears_and_oil_at_one_temperature(oil):
    """axis_quantity = "bulk_and_oil": the slice at 80 degC equals the single table of the scene
    with the oil at 80 degC AND both gears at 80 degC (seed 004 eq 27-28 on top of the film);
    FMU input gearbox_temperature."""
    # standard temperature 40 degC = the oil's: the 40 degC node is the scene's table (no rebuild)
    text = OIL_TEXT + ("\n[thermal]\naxis_quantity = \"bulk_and_oil\"\noil_alpha = \"constant\"\n"
                       "standard_temperature_C = 40.0\n"
                       "temperature_axis_C = [40.0, 80.0]\n")
    _, tab = _oil_tables(text)
    _, single = _oil_tables(OIL_TEXT.replace("temperature_C = 40.0", "temperature_C = 80.0")
                            + "\n[thermal]\nstandard_temperature_C = 40.0\npinion_temperature_C = 80.0\n"
                              "gear_temperature_C = 80.0\n")
    _, _, oil_only = oil                                                  # oil at 80 degC, gears standard
    assert np.array_equal(tab.at_temperature(80.0).k_N_per_m, single.k_N_per_m)
    assert np.all(single.k_N_per_m <= oil_only.k_N_per_m)                 # seed 004: 40 K above t0 lowers k
    assert np.mean(single.k_total_N_per_m()) < (1 - 1e-3) * np.mean(oil_only.k_total_N_per_m())
    assert tab.temperature_input == "gearbox_temperature"
    names = [v.name for v in expand_variables(load_spec(), tab.slots, ("gearbox_temperature_axis",))]
    assert "gearbox_temperature" in names and "oil_temperature" not in names


def test_oil_axis_refused_without_a_lubricated_contact_model():
    """Hertz contact uses no lubricant: the scene reader and the table builder refuse an oil axis."""
    from gearfmu.assembly.precompute import PrecomputeInputError, precompute_tables
    from gearfmu.scene.reader import SceneError

    hertz = (REPO / "examples" / "scenes" / "seed004_pair1.toml").read_text()
    with pytest.raises(SceneError, match=r"thermal\.axis_quantity: 'oil'.*uses no lubricant"):
        load_scene(hertz + "\n[thermal]\naxis_quantity = \"oil\"\ntemperature_axis_C = [40.0, 80.0]\n")
    sc = load_scene(hertz + "\n[thermal]\ntemperature_axis_C = [40.0, 80.0]\n")
    import dataclasses
    th = dataclasses.replace(sc.thermal, axis_quantity="oil", lubricant=sc.lubricant)
    with pytest.raises(PrecomputeInputError, match="axis_quantity: 'oil'.*'hertz' uses no lubricant"):
        precompute_tables(sc.pair, sc.mesh, points_per_mesh=8, nominal_torque_Nm=381.97, thermal=th)
    eta_only = OIL_TEXT.replace("kinematic_viscosity_40C_cSt = 320.0", "eta0_Pas = 0.1").replace(
        "kinematic_viscosity_100C_cSt = 38.5", "")
    with pytest.raises(SceneError, match=r"lubricant\.eta0_Pas: .*viscosity-temperature law"):
        load_scene(eta_only + "\n[thermal]\naxis_quantity = \"oil\"\ntemperature_axis_C = [40.0, 80.0]\n")


def test_automatic_max_step_of_a_temperature_axis_scene(seed004):
    """solver.max_step_s = "auto" with a temperature axis (gearfmu build of such a scene): the
    bound of the stiffest slice, i.e. the smallest of choose_max_step_s over the axis slices."""
    from gearfmu.dynamics.native import choose_max_step_s
    from gearfmu.pipeline import max_step_for

    _, hot = seed004
    sc = load_scene(SEED004_SCENE + "\n[thermal]\ntemperature_axis_C = [10.0, 30.0, 70.0]\n")
    assert sc.solver.max_step_s is None
    w = sc.operating.speed_rad_s
    per = [choose_max_step_s(hot.at_temperature(t), w) for t in (10.0, 30.0, 70.0)]
    assert max_step_for(sc, hot) == min(per)


def test_oil_axis_default_alpha_follows_roelands(oil):
    """Default oil_alpha = "roelands": along the oil axis the pressure-viscosity coefficient
    follows Roelands (1966) with Z constant, alpha(T) = Z (ln eta0(T) + 9.67) / p0,
    p0 = 1.96e8 Pa, Z fixed by the [lubricant] alpha at the lubricant temperature (written out
    here, not taken from gearfmu).  The 80 degC slice equals the table of the scene written at
    80 degC with that alpha (an independent precompute run; 1e-12: the scene reader scales
    1/GPa to 1/Pa), and the film at 80 degC is thinner than with a constant alpha, so the
    mesh stiffness is higher (seed 000 eq 8: k_film = A B / h)."""
    sc, tab = _oil_tables(OIL_TEXT + f"\n[thermal]\naxis_quantity = \"oil\"\ntemperature_axis_C = {list(OIL_AXIS)}\n")
    _, const, single80_const = oil
    eta = tab.provenance["thermal"]["oil"]["eta0_Pas"]
    z = 20e-9 * 1.96e8 / (math.log(eta[0]) + 9.67)
    alpha80 = z * (math.log(eta[1]) + 9.67) / 1.96e8
    assert tab.provenance["thermal"]["oil"]["alpha_Pa_inv"] == pytest.approx([20e-9, alpha80], rel=1e-12)
    assert 14e-9 < alpha80 < 18e-9                                          # falls with temperature
    _, single80 = _oil_tables(OIL_TEXT.replace("temperature_C = 40.0", "temperature_C = 80.0")
                              .replace("pressure_viscosity_GPa_inv = 20.0",
                                       f"pressure_viscosity_GPa_inv = {alpha80 * 1e9!r}"))
    at80 = tab.at_temperature(80.0)
    np.testing.assert_allclose(at80.k_N_per_m, single80.k_N_per_m, rtol=1e-12)
    assert np.array_equal(tab.at_temperature(40.0).k_N_per_m, const.at_temperature(40.0).k_N_per_m)
    assert np.mean(at80.k_total_N_per_m()) > np.mean(single80_const.k_total_N_per_m())
