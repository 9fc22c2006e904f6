"""The drivetrain scene: gear-pair stages joined by shafts, with motor and load (TOML), and :func:`load_drivetrain`.

A drivetrain file has a top-level ``[drivetrain]`` table (a gear-pair scene has ``[scene]``):

* ``[motor]`` and ``[load]``: the two end bodies (inertia; the motor's start torque and speed,
  the load's start torque), each a torque input or not;
* ``[[stage]]``: the gear-pair stages, each a pair scene by path (``scene = "pair.toml"``,
  relative to the drivetrain file) or inline (``[stage.pair]`` with the pair scene's tables),
  read by :func:`gearfmu.scene.reader.load_scene` with its own gears, contact model, errors and
  tables options;
* ``[[shaft]]``: the links between the parts ``motor``, ``load``, ``<stage>.pinion`` and
  ``<stage>.gear``: an elastic shaft (stiffness given, or from diameter, bore, length and
  material) with damping, or ``rigid = true``;
* ``[solver]`` (integrator, largest internal step) and ``[run]`` (stop time, output interval).

Every key, unit, default and range is in :data:`DRIVETRAIN_SCHEMA`, documented in
docs/scene.md "Drivetrain scenes"; the model it feeds is docs/gearbox.md.  All problems are
collected and raised together as one :class:`gearfmu.scene.options.SceneError` naming each
key path (``shaft[1].stiffness_Nm_per_rad: must be a number in (0, 1e+12], got -3``); a
stage's own scene problems come back under the stage's key (``stage[0].pair.gears.module_mm:
...``).

Operating point of the stages: the kinematic ratio of every part follows from the base radii
(``g = 1`` for the motor, a shaft keeps it, a mesh multiplies it by Rb_pinion/Rb_gear); stage
``s`` then runs at pinion speed ``g_p * omega_motor`` and transmits the pinion torque
``T_motor / g_p`` in steady state.  These replace the stage scene's own ``[operating]`` torque
and speed (its ranges and table options are kept); :attr:`DrivetrainScene.notes` says so for
every stage, and warns when a stage's torque lies outside its tables' torque axis.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

try:  # Python >= 3.11
    import tomllib as _toml
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as _toml  # type: ignore[no-redef]

from ..common.topology import drivetrain_tree, planetary_sun_torque, willis_ratio
from ..common.vocabulary import DEFAULT_INTEGRATOR, GEARBOX_INTEGRATORS
from ..gear.geometry import pair_geometry
from .options import RPM_TO_RAD_S, Scene, SceneError, default_output_interval_s
from .planetary import PLANETARY_SCHEMA, PLANETARY_SUBTABLES, PlanetarySpec, read_planetary
from .reader import load_scene
from .schema import AUTO, REQUIRED, Key
from .toml_writer import dumps_toml
from .validate import Reader, describe, sub

__all__ = ["DRIVETRAIN_SCHEMA", "DRIVETRAIN_SUBTABLES", "EndSpec", "StageRef", "ShaftSpec", "DrivetrainScene",
           "load_drivetrain", "is_drivetrain_file", "SHAFT_DAMPING_RATIO_DEFAULT", "STEEL"]

#: damping ratio of a shaft that names none (docs/scene.md "[[shaft]]")
SHAFT_DAMPING_RATIO_DEFAULT = 0.02
#: the shaft material when none is named: steel, E = 206 GPa, nu = 0.3, rho = 7850 kg/m^3
STEEL = {"youngs_modulus_GPa": 206.0, "poisson_ratio": 0.3, "density_kg_m3": 7850.0}


def _f(name, unit, default, doc, lo=None, hi=None, lo_open=False, hi_open=False, scale=1.0, kind="float"):
    return Key(name, kind, unit, default, doc, lo, hi, lo_open, hi_open, (), scale)


#: every table of a drivetrain scene and its keys (docs/scene.md "Drivetrain scenes")
DRIVETRAIN_SCHEMA: Dict[str, Tuple[Key, ...]] = {
    "drivetrain": (
        Key("name", "str", "-", "drivetrain", "short name (also the default model name)"),
        Key("description", "str", "-", "", "free text"),
        Key("model_name", "identifier", "-", None, "model name / identifier of the gearbox FMU (C identifier; "
            "none = from drivetrain.name)"),
    ),
    "motor": (
        _f("inertia_kgm2", "kg*m^2", REQUIRED, "inertia of the motor rotor (the upstream end body)", 0.0, 1e6,
           lo_open=True),
        _f("torque_Nm", "N*m", REQUIRED, "motor torque (positive drives): the start value of the input and the "
           "torque that sets every stage's operating point", 0.0, 1e7, lo_open=True),
        _f("speed_rpm", "rpm", REQUIRED, "initial motor speed; sets every stage's operating speed", 0.0, 1e6,
           lo_open=True, scale=RPM_TO_RAD_S),
        Key("torque_input", "bool", "-", True, "the motor torque is an input (false: no external torque on the "
            "motor, a free end)"),
    ),
    "load": (
        _f("inertia_kgm2", "kg*m^2", REQUIRED, "inertia of the driven machine (the downstream end body)", 0.0,
           1e9, lo_open=True),
        _f("torque_Nm", "N*m", None, "load torque (positive resists): the start value of the input; none = the "
           "torque that balances the motor torque in steady state, T_motor times the total ratio", 0.0, 1e10),
        Key("torque_input", "bool", "-", True, "the load torque is an input (false: no external torque on the "
            "load, a free end)"),
    ),
    "stage": (
        Key("name", "str", "-", REQUIRED, "stage name (letters, digits, _); its parts are <name>.pinion and "
            "<name>.gear, its outputs <name>.dte, ..."),
        Key("scene", "str", "-", None, "the stage's gear-pair scene file, relative to the drivetrain file (or "
            "an inline [stage.pair] table)"),
        _f("damping_ratio", "1", None, "mesh damping ratio zeta of this stage (none = the stage scene's "
           "fmu.damping_ratio)", 0.0, 1.0),
    ),
    "shaft": (
        Key("name", "str", "-", REQUIRED, "shaft name (letters, digits, _); its output is <name>.torque"),
        Key("from", "str", "-", REQUIRED, "one end: motor, load, <stage>.pinion or <stage>.gear"),
        Key("to", "str", "-", REQUIRED, "the other end (the order does not matter: the torque output is "
            "positive when the shaft drives away from the motor)"),
        Key("rigid", "bool", "-", False, "a rigid coupling: the two ends become one body (no stiffness or "
            "damping keys)"),
        _f("stiffness_Nm_per_rad", "N*m/rad", None, "torsional stiffness (or give diameter_mm and length_mm)",
           0.0, 1e12, lo_open=True),
        _f("diameter_mm", "mm", None, "outer diameter of a uniform round shaft", 0.0, 1e4, lo_open=True,
           scale=1e-3),
        _f("bore_mm", "mm", 0.0, "bore diameter of a hollow shaft (0 = solid)", 0.0, 1e4, scale=1e-3),
        _f("length_mm", "mm", None, "twisting length between the two ends", 0.0, 1e5, lo_open=True, scale=1e-3),
        _f("shear_modulus_GPa", "GPa", None, "shear modulus G (none = E/(2(1 + nu)))", 0.0, 1000.0, lo_open=True,
           scale=1e9),
        _f("youngs_modulus_GPa", "GPa", STEEL["youngs_modulus_GPa"], "Young's modulus E of the shaft material",
           0.0, 1000.0, lo_open=True, scale=1e9),
        _f("poisson_ratio", "1", STEEL["poisson_ratio"], "Poisson's ratio nu of the shaft material", 0.0, 0.5,
           hi_open=True),
        _f("density_kg_m3", "kg/m^3", STEEL["density_kg_m3"], "density of the shaft material (its inertia "
           "rho*J*L, lumped half to each end)", 0.0, 30000.0, lo_open=True),
        _f("inertia_kgm2", "kg*m^2", None, "the shaft's own inertia, lumped half to each end (none = rho*J*L "
           "from the dimensions, else 0)", 0.0, 1e6),
        _f("damping_ratio", "1", None, f"damping ratio zeta of the shaft: c = 2 zeta sqrt(k I_a I_b/(I_a + I_b)) "
           f"with the inertias of its two end bodies (none and no damping_Nms_per_rad: "
           f"{SHAFT_DAMPING_RATIO_DEFAULT})", 0.0, 1.0),
        _f("damping_Nms_per_rad", "N*m*s/rad", None, "torsional damping coefficient c (instead of "
           "damping_ratio)", 0.0, 1e9),
    ),
    "solver": (
        Key("integrator", "enum", "-", DEFAULT_INTEGRATOR, "integrator of the gearbox solver (docs/gearbox.md)",
            choices=GEARBOX_INTEGRATORS),
        _f("max_step_s", "s", AUTO, "largest internal step, or \"auto\" (docs/gearbox.md \"Step\")", 0.0, 1.0,
           lo_open=True, kind="float_or_auto"),
    ),
    "run": (
        _f("stop_time_s", "s", 0.1, "simulated time of `gearfmu simulate`", 0.0, 1e6, lo_open=True),
        _f("output_interval_s", "s", AUTO, "output (communication) interval, or \"auto\" (at least 20 samples "
           "per mesh period of the fastest stage)", 0.0, 1e3, lo_open=True, kind="float_or_auto"),
    ),
    **PLANETARY_SCHEMA,
}

#: sub-tables that may appear inside a drivetrain table (besides its keys)
DRIVETRAIN_SUBTABLES = {
    "": ("drivetrain", "motor", "load", "stage", "shaft", "solver", "run", "planetary"),
    "stage": ("pair",),
    **PLANETARY_SUBTABLES,
}

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class _RowSchema(dict):
    """A drivetrain table mapping (keys or sub-tables), looked up with the row index of an array of
    tables removed (``stage[1]`` reads the keys of ``stage``)."""

    def get(self, path, default=None):
        return super().get(re.sub(r"\[\d+\]", "", path), default)


# ============================================================== result dataclasses
@dataclass(frozen=True)
class EndSpec:
    """An end body (SI): ``name`` ``"motor"`` or ``"load"``, inertia (kg*m^2), start torque (N*m;
    the load's None = the balancing torque), start speed (rad/s, motor only), and whether the
    torque is an input."""

    name: str
    inertia_kgm2: float
    torque_Nm: Optional[float]
    speed_rad_s: Optional[float]
    torque_input: bool = True


@dataclass(frozen=True)
class StageRef:
    """A stage: its name, its pair scene (operating point replaced by the drivetrain's, see
    the module docstring), where the scene came from, the mesh damping ratio and law, the
    base radii of its pinion and gear (m, from the geometry), and its kinematic ratio
    ``ratio_pinion`` (pinion speed / motor speed)."""

    name: str
    scene: Scene
    source: str
    damping_ratio: float
    damping_model: str
    base_radius_pinion_m: float
    base_radius_gear_m: float
    ratio_pinion: float

    @property
    def pinion(self) -> str:
        return f"{self.name}.pinion"

    @property
    def gear(self) -> str:
        return f"{self.name}.gear"

    @property
    def pinion_torque_Nm(self) -> float:
        """The static pinion torque of the stage (N*m) at the drivetrain's motor torque."""
        return float(self.scene.operating.torque_Nm)


@dataclass(frozen=True)
class ShaftSpec:
    """A shaft (SI): ``a``, ``b`` its end parts; ``rigid`` or the stiffness (N*m/rad), the damping
    (a ratio, or N*m*s/rad), its own inertia (kg*m^2, lumped half to each end) and how the
    stiffness was obtained (``"given"`` or ``"dimensions"``)."""

    name: str
    a: str
    b: str
    rigid: bool
    stiffness_Nm_per_rad: Optional[float]
    damping_ratio: Optional[float]
    damping_Nms_per_rad: Optional[float]
    inertia_kgm2: float
    stiffness_from: str


@dataclass(frozen=True)
class DrivetrainScene:
    """A validated drivetrain scene (SI).  ``parts``, ``links`` and ``ratio`` (part -> speed /
    motor speed) describe the topology (:func:`gearfmu.common.topology.drivetrain_tree`);
    ``notes`` are the lines a build prints (replaced operating points, torque-axis warnings)."""

    name: str
    description: str
    model_name: str
    text: str
    source_path: Optional[str]
    motor: EndSpec
    load: EndSpec
    stages: Tuple[StageRef, ...]
    shafts: Tuple[ShaftSpec, ...]
    integrator: str
    max_step_s: Optional[float]
    stop_time_s: float
    output_interval_s: float
    output_interval_auto: bool
    ratio: Dict[str, float]
    notes: Tuple[str, ...] = ()
    planetaries: Tuple[PlanetarySpec, ...] = ()

    @property
    def parts(self) -> Tuple[str, ...]:
        return ("motor", "load") + tuple(p for s in self.stages for p in (s.pinion, s.gear)) + tuple(
            s.port(p) for s in self.planetaries for p in s.free_ports)

    @property
    def links(self) -> Tuple[Tuple[str, str, str], ...]:
        """``(kind, a, b)`` of every stage's mesh, every planetary stage's two free ports, then every
        shaft (in file order)."""
        return tuple(("mesh", s.pinion, s.gear) for s in self.stages) + tuple(
            ("planetary",) + tuple(s.port(p) for p in s.free_ports) for s in self.planetaries) + tuple(
            ("rigid" if s.rigid else "shaft", s.a, s.b) for s in self.shafts)

    @property
    def total_ratio(self) -> float:
        """Motor speed / load speed (the product of the stages' tooth ratios z_gear/z_pinion)."""
        return 1.0 / self.ratio["load"]

    @property
    def load_torque_Nm(self) -> float:
        """The load's start torque (N*m): the given one, else the balancing T_motor * total ratio."""
        if self.load.torque_Nm is not None:
            return float(self.load.torque_Nm)
        return float(self.motor.torque_Nm) * self.total_ratio


# ============================================================== reading
def is_drivetrain_file(path: Union[str, Path]) -> bool:
    """True when the TOML file at ``path`` has a top-level ``[drivetrain]`` table (False when it
    cannot be read or parsed: the pair-scene reader then names the problem)."""
    try:
        data = _toml.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, _toml.TOMLDecodeError):
        return False
    return isinstance(data.get("drivetrain"), dict)


def _identifier(r: Reader, path: str, v: Any) -> Optional[str]:
    if v is None:
        return None
    if not _NAME.fullmatch(v):
        r.add(path, f"must be a name of letters, digits and _ (not starting with a digit), got {v!r}")
        return None
    return v


def _rows(r: Reader, data: Any, name: str) -> List[Tuple[str, Any, Dict[str, Any]]]:
    """The rows of the array of tables ``[[name]]``: (key path, raw table, values)."""
    raw = sub(data, name)
    if raw is None:
        return []
    if not isinstance(raw, list) or not all(isinstance(t, dict) for t in raw):
        r.add(name, f"must be an array of tables [[{name}]], got {describe(raw)}")
        return []
    return [(f"{name}[{i}]", t, r.table(t, f"{name}[{i}]")) for i, t in enumerate(raw)]


def _inside(rng) -> float:
    """A positive value inside ``rng`` ([low, high], as written) when it is one, else 1."""
    if isinstance(rng, list) and len(rng) == 2 and all(isinstance(v, (int, float)) for v in rng):
        for v in (rng[0], 0.5 * (rng[0] + rng[1]), rng[1]):
            if v > 0:
                return float(v)
    return 1.0


def _stage_scene(r: Reader, path: str, raw: Dict[str, Any], vals: Dict[str, Any], base: Path):
    """(Scene, source, whether the scene named its own operating torque or speed) of one [[stage]]
    row, or None (problem recorded with the row's key path: the pair scene's own problems under
    it).  An inline pair without them gets a placeholder that the drivetrain replaces."""
    inline = raw.get("pair")
    file = vals["scene"]
    if (inline is None) == (file is None):
        r.add(path, "give either scene = \"FILE.toml\" (a gear-pair scene) or an inline [stage.pair] table"
              if inline is None else "give either scene or [stage.pair], not both")
        return None
    if inline is not None:
        if not isinstance(inline, dict):
            r.add(f"{path}.pair", f"must be a table (the pair scene's sections), got {describe(inline)}")
            return None
        data = dict(inline)
        op = data.get("operating")
        own = isinstance(op, dict) and ("torque_Nm" in op or "speed_rpm" in op)
        if op is None:  # the drivetrain sets the operating point; the pair reader needs one
            data["operating"] = {"torque_Nm": 1.0, "speed_rpm": 1.0}
        elif isinstance(op, dict):  # a placeholder inside the scene's own ranges
            data["operating"] = {"torque_Nm": _inside(op.get("torque_range_Nm")),
                                 "speed_rpm": _inside(op.get("speed_range_rpm")), **op}
        prefix, source = f"{path}.pair", "inline"
        try:
            text = dumps_toml(data)
        except (TypeError, ValueError) as exc:
            r.add(f"{path}.pair", f"cannot be written as TOML: {exc}")
            return None
        src: Any = text
    else:
        p = Path(file)
        if not p.is_absolute():
            p = base / p
        prefix, source, src, own = f"{path}.scene ({p})", str(p), p, True
        if not p.is_file():
            r.add(f"{path}.scene", f"scene file not found: {p}")
            return None
    try:
        return load_scene(src), source, own
    except SceneError as exc:
        for key, reason in exc.problems:
            r.add(f"{prefix}.{key}" if key and not key.startswith("<") else prefix, reason)
        return None


def _shaft(r: Reader, path: str, raw: Dict[str, Any], v: Dict[str, Any]) -> Optional[ShaftSpec]:
    """A [[shaft]] row's stiffness, damping and inertia (SI), or None (problems recorded)."""
    n0 = len(r.problems)
    stiff_keys = ("stiffness_Nm_per_rad", "diameter_mm", "length_mm", "shear_modulus_GPa", "youngs_modulus_GPa",
                  "poisson_ratio")
    damp_keys = ("damping_ratio", "damping_Nms_per_rad")
    if v["rigid"]:
        bad = [k for k in stiff_keys + damp_keys if k in raw and k not in ("diameter_mm", "length_mm")]
        for k in bad:
            r.add(f"{path}.{k}", "a rigid shaft has no stiffness or damping (remove the key or rigid = true)")
    given = "stiffness_Nm_per_rad" in raw
    dims = "diameter_mm" in raw or "length_mm" in raw
    if not v["rigid"] and given and dims:
        r.add(f"{path}.stiffness_Nm_per_rad", "give either stiffness_Nm_per_rad or the dimensions (diameter_mm, "
                                              "length_mm), not both")
    if not v["rigid"] and not given and not dims:
        r.add(path, "needs its stiffness: stiffness_Nm_per_rad, or diameter_mm and length_mm (or rigid = true)")
    if dims and ("diameter_mm" in raw) != ("length_mm" in raw):
        missing = "length_mm" if "diameter_mm" in raw else "diameter_mm"
        r.add(f"{path}.{missing}", "missing: a shaft's dimensions need diameter_mm and length_mm")
    if "shear_modulus_GPa" in raw and ("youngs_modulus_GPa" in raw or "poisson_ratio" in raw):
        r.add(f"{path}.shear_modulus_GPa", "give either shear_modulus_GPa or youngs_modulus_GPa/poisson_ratio")
    if "damping_ratio" in raw and "damping_Nms_per_rad" in raw:
        r.add(f"{path}.damping_ratio", "give either damping_ratio or damping_Nms_per_rad, not both")
    d, bore = v["diameter_mm"], v["bore_mm"]
    if d is not None and bore is not None and not bore < d:
        r.add(f"{path}.bore_mm", f"must be smaller than diameter_mm ({d * 1e3:g} mm), got {bore * 1e3:g}")
    if len(r.problems) > n0 or any(v[k] is None for k in ("rigid", "bore_mm", "density_kg_m3")):
        return None
    k = v["stiffness_Nm_per_rad"]
    inertia = 0.0
    src = "given"
    if d is not None and v["length_mm"] is not None:
        L = v["length_mm"]
        J = math.pi * (d ** 4 - bore ** 4) / 32.0         # polar second moment of area (m^4)
        inertia = v["density_kg_m3"] * J * L                # rho J L: a hollow cylinder's polar inertia
        if not v["rigid"]:
            G = v["shear_modulus_GPa"]
            if G is None:
                if v["youngs_modulus_GPa"] is None or v["poisson_ratio"] is None:
                    return None
                G = v["youngs_modulus_GPa"] / (2.0 * (1.0 + v["poisson_ratio"]))
            k = G * J / L                                   # uniform shaft in torsion
            src = "dimensions"
    if v["inertia_kgm2"] is not None:
        inertia = v["inertia_kgm2"]
    zeta, c = v["damping_ratio"], v["damping_Nms_per_rad"]
    if not v["rigid"] and zeta is None and c is None:
        zeta = SHAFT_DAMPING_RATIO_DEFAULT
    return ShaftSpec(name=v["name"], a=v["from"], b=v["to"], rigid=bool(v["rigid"]),
                     stiffness_Nm_per_rad=None if v["rigid"] else k, damping_ratio=None if v["rigid"] else zeta,
                     damping_Nms_per_rad=None if v["rigid"] else c, inertia_kgm2=float(inertia),
                     stiffness_from="rigid" if v["rigid"] else src)


def _ratios(tree, links, radii, planetaries=None) -> Dict[str, float]:
    """Speed / motor speed of every part from the tree's breadth-first edges: 1 for the motor's
    body, a shaft keeps it, a mesh multiplies it by Rb_pinion/Rb_gear (``radii``: stage pinion
    name -> (Rb_p, Rb_g)), a planetary stage by Willis' ratio of its two free ports
    (``planetaries``: stage name -> PlanetarySpec)."""
    g = [1.0] * len(tree.bodies)
    for li, up, down in tree.edges:
        kind, a, b = links[li]
        if kind == "mesh":
            g[down] = g[up] * (radii[a][0] / radii[a][1])
        elif kind == "planetary":
            st = planetaries[a.split(".")[0]]
            pu, pd = (a, b) if tree.body_of[a] == up else (b, a)
            g[down] = g[up] * willis_ratio(st.held, pu.split(".")[1], pd.split(".")[1], *st.sun_ring)
        else:
            g[down] = g[up]
    return {p: g[i] for p, i in tree.body_of.items()}


def _build(data: Dict[str, Any], text: str, source_path: Optional[str]) -> DrivetrainScene:
    r = Reader(_RowSchema(DRIVETRAIN_SCHEMA), _RowSchema(DRIVETRAIN_SUBTABLES))
    r.table(data, "")
    dt = r.table(sub(data, "drivetrain"), "drivetrain", required=True)
    motor = r.table(sub(data, "motor"), "motor", required=True)
    load = r.table(sub(data, "load"), "load", required=True)
    sol = r.table(sub(data, "solver"), "solver")
    run = r.table(sub(data, "run"), "run")
    base = Path(source_path).parent if source_path else Path(".")
    stages_raw = _rows(r, data, "stage")
    shafts_raw = _rows(r, data, "shaft")
    plan_raw = _rows(r, data, "planetary")
    if not stages_raw and sub(data, "stage") is None and not plan_raw and sub(data, "planetary") is None:
        r.add("stage", "missing: a drivetrain needs at least one [[stage]] or [[planetary]]")
    if not load["torque_input"] and load["torque_Nm"] is not None and "torque_Nm" in (sub(data, "load") or {}):
        r.add("load.torque_Nm", "the load has no torque input (torque_input = false); remove torque_Nm")
    if motor["torque_input"] is False and not load["torque_input"]:
        r.add("motor.torque_input", "at least one end must be a torque input")

    # ---------------- stages: names and pair scenes
    names: Dict[str, str] = {}
    stage_scenes = []
    for path, raw, v in stages_raw:
        nm = _identifier(r, f"{path}.name", v["name"])
        if nm is not None and nm in ("motor", "load"):
            r.add(f"{path}.name", f"{nm!r} names an end body; choose another stage name")
            nm = None
        if nm is not None and nm in names:
            r.add(f"{path}.name", f"{nm!r} is already the name of {names[nm]}")
            nm = None
        if nm is not None:
            names[nm] = path
        got = _stage_scene(r, path, raw, v, base)
        stage_scenes.append((path, nm, v, got))
    plans: List[Tuple[str, PlanetarySpec]] = []
    plan_problem = False
    for path, raw, v in plan_raw:
        nm = _identifier(r, f"{path}.name", v["name"])
        if nm is not None and (nm in ("motor", "load") or nm in names):
            r.add(f"{path}.name", f"{nm!r} is already a name in this drivetrain")
            nm = None
        if nm is not None:
            names[nm] = path
        spec = read_planetary(r, path, raw, v) if nm is not None else None
        if spec is None:
            plan_problem = True     # its ports are unknown: the shafts' ends are not reported again
        else:
            plans.append((path, spec))
    parts = ["motor", "load"] + [f"{nm}.{role}" for _, nm, _, _ in stage_scenes if nm for role in ("pinion", "gear")]
    parts += [s.port(p) for _, s in plans for p in s.free_ports]
    held = {s.port(s.held): s.name for _, s in plans}
    driven = {s.port(s.held) for _, s in plans if s.driven_speed_rad_s is not None}
    # a stage without a valid name has no parts: its shafts' ends are not reported again
    stage_name_problem = any(nm is None for _, nm, _, _ in stage_scenes) or plan_problem

    # ---------------- shafts: names, ends, stiffness
    shaft_names: Dict[str, str] = {}
    shafts: List[Tuple[str, Optional[ShaftSpec]]] = []
    for path, raw, v in shafts_raw:
        nm = _identifier(r, f"{path}.name", v["name"])
        if nm is not None and (nm in shaft_names or nm in names or nm in ("motor", "load")):
            r.add(f"{path}.name", f"{nm!r} is already a name in this drivetrain")
        elif nm is not None:
            shaft_names[nm] = path
        for end in ("from", "to"):
            if v[end] in held:
                how = "driven through its torsional support by its drive" if v[end] in driven else \
                    "grounded through its torsional support"
                r.add(f"{path}.{end}", f"{v[end]!r} is the held port of planetary stage {held[v[end]]!r} ({how}): no "
                                       "shaft may join it")
            elif v[end] is not None and v[end] not in parts and not stage_name_problem:
                r.add(f"{path}.{end}", f"{v[end]!r} is not a part; parts are {', '.join(parts)}")
        shafts.append((path, _shaft(r, path, raw, v)))
    if r.problems:
        raise SceneError(r.problems, source=source_path or "drivetrain")

    # ---------------- topology: one tree from the motor, pinions on the motor side
    specs = [s for _, s in shafts]
    # meshes first: a loop is then reported at the shaft that closes it
    links = [("mesh", f"{nm}.pinion", f"{nm}.gear") for _, nm, _, _ in stage_scenes]
    links += [("planetary",) + tuple(s.port(p) for p in s.free_ports) for _, s in plans]
    links += [("rigid" if s.rigid else "shaft", s.a, s.b) for s in specs]
    link_path = [p for p, _, _, _ in stage_scenes] + [p for p, _ in plans] + [p for p, _ in shafts]
    tree = drivetrain_tree(parts, links, "motor")
    for li, part, reason in tree.problems:
        r.add(link_path[li] if li is not None else _part_key(part, names), reason)
    if not r.problems:
        path_edges = {tree.edges[e][0] for e in tree.path(tree.body_of["motor"], tree.body_of["load"])}
        for li, (kind, a, _) in enumerate(links):
            if kind in ("mesh", "planetary") and li not in path_edges:
                r.add(link_path[li], f"stage {a.split('.')[0]!r} is not on the power path from the motor to the "
                                     "load (a stage that transmits no torque is not supported)")
    if r.problems:
        raise SceneError(r.problems, source=source_path or "drivetrain")

    # ---------------- ratios and the stages' operating points
    radii = {}
    for path, nm, v, (sc, src, own) in stage_scenes:
        geo = pair_geometry(sc.pair)
        radii[f"{nm}.pinion"] = (float(geo.rb1_m), float(geo.rb2_m))
    ratio = _ratios(tree, links, radii, {s.name: s for _, s in plans})
    t_motor, w_motor = motor["torque_Nm"], motor["speed_rpm"]
    notes = []
    planetaries, mesh_speeds = _planetary_operating_points(plans, len(stage_scenes), links, tree, ratio, t_motor,
                                                          w_motor, notes)
    stages = []
    for path, nm, v, (sc, src, own) in stage_scenes:
        g = ratio[f"{nm}.pinion"]
        t_p, w_p = t_motor / g, w_motor * g
        op = sc.operating
        if own:
            notes.append(f"{nm}: operating point {op.torque_Nm:.6g} N*m, {op.speed_rpm:.6g} rpm of {src} replaced "
                         f"by the drivetrain's {t_p:.6g} N*m, {w_p / RPM_TO_RAD_S:.6g} rpm")
        rng = op.torque_range_Nm
        if op.torque_points > 1 and rng is not None and not rng[0] <= t_p <= rng[1]:
            notes.append(f"WARNING {nm}: pinion torque {t_p:.6g} N*m outside its tables' torque axis "
                         f"[{rng[0]:.6g}, {rng[1]:.6g}] N*m (operating.torque_range_Nm of {src}); the lookup "
                         "clamps to the axis")
        sc = replace(sc, operating=replace(op, torque_Nm=t_p, speed_rad_s=w_p))
        zeta = v["damping_ratio"] if v["damping_ratio"] is not None else sc.fmu.damping_ratio
        stages.append(StageRef(name=nm, scene=sc, source=src, damping_ratio=float(zeta),
                               damping_model=sc.solver.damping_model, base_radius_pinion_m=radii[f"{nm}.pinion"][0],
                               base_radius_gear_m=radii[f"{nm}.pinion"][1], ratio_pinion=g))
    dt_auto = run["output_interval_s"] is None
    mesh_speeds += [(s.scene.operating.speed_rad_s, s.scene.pair.pinion.teeth) for s in stages]
    if dt_auto:
        dt_out = min(default_output_interval_s(w, z) for w, z in mesh_speeds)
        dt_out = min(dt_out, run["stop_time_s"])
    else:
        dt_out = run["output_interval_s"]
        if dt_out > run["stop_time_s"]:
            r.add("run.output_interval_s", f"must not exceed run.stop_time_s ({run['stop_time_s']:g} s), got "
                                           f"{dt_out:g}")
            raise SceneError(r.problems, source=source_path or "drivetrain")
    name = dt["name"]
    model_name = dt["model_name"] or _model_name(name)
    return DrivetrainScene(
        name=name, description=dt["description"], model_name=model_name, text=text, source_path=source_path,
        motor=EndSpec("motor", motor["inertia_kgm2"], t_motor, w_motor, bool(motor["torque_input"])),
        load=EndSpec("load", load["inertia_kgm2"], load["torque_Nm"], None, bool(load["torque_input"])),
        stages=tuple(stages), shafts=tuple(specs), integrator=sol["integrator"], max_step_s=sol["max_step_s"],
        stop_time_s=run["stop_time_s"], output_interval_s=dt_out, output_interval_auto=dt_auto, ratio=ratio,
        notes=tuple(notes), planetaries=tuple(planetaries))


def _planetary_operating_points(plans, first_link: int, links, tree, ratio, t_motor: float, w_motor: float,
                                notes: list):
    """(the planetary stages with their ports' kinematic ratios and the sun's static torque, the (sun
    mesh speed rad/s, sun teeth) of each): the port nearer the motor takes T_motor/g of it; a note
    per stage (its form, model, planets, held port, sun torque and mesh frequency)."""
    planetaries, mesh_speeds = [], []
    for li, (path, st) in enumerate(plans, start=first_link):
        edge = next(e for e in tree.edges if e[0] == li)
        a, b = links[li][1], links[li][2]
        up = (a if tree.body_of[a] == edge[1] else b).split(".")[1]
        g = {p: (ratio[st.port(p)] if p != st.held else 0.0) for p in ("sun", "carrier", "ring")}
        t_sun = planetary_sun_torque(up, t_motor / g[up], *st.sun_ring)
        planetaries.append(replace(st, ratio=g, sun_torque_Nm=abs(t_sun)))
        w_sun_mesh = (abs(g["sun"] - g["carrier"]) * w_motor if st.driven_speed_rad_s is None
                      else abs(_sun_mesh_speed(st, up, g[up] * w_motor)))
        mesh_speeds.append((w_sun_mesh, st.teeth[0]))
        how = "held" if st.driven_speed_rad_s is None else f"driven at {st.driven_speed_rad_s / RPM_TO_RAD_S:.6g} rpm"
        notes.append(f"{st.name}: planetary stage ({st.form}, {st.model}, {st.planets} planets, {st.held} {how}), sun "
                     f"torque {abs(t_sun):.6g} N*m, sun mesh frequency "
                     f"{st.teeth[0] * w_sun_mesh / (2 * math.pi):.6g} Hz")
    return planetaries, mesh_speeds


def _sun_mesh_speed(st, up: str, w_up: float) -> float:
    """w_s - w_c (rad/s) of a stage whose port ``up`` turns at ``w_up`` and whose held port stands still
    or turns at its drive's speed (Willis: z_s (w_s - w_c) + z_r (w_r - w_c) = 0)."""
    zs, zr = st.sun_ring
    w = {up: w_up, st.held: st.driven_speed_rad_s or 0.0}
    if "carrier" in w:
        other = "sun" if "ring" in w else "ring"
        w[other] = w["carrier"] + (zr * (w["carrier"] - w["ring"]) / zs if other == "sun"
                                   else zs * (w["carrier"] - w["sun"]) / zr)
    else:
        w["carrier"] = (zs * w["sun"] + zr * w["ring"]) / (zs + zr)
    return w["sun"] - w["carrier"]


def _part_key(part: Optional[str], stage_paths: Dict[str, str]) -> str:
    """The key path to name for a part (a stage's row, or the motor / load table)."""
    if part is None:
        return "shaft"
    if "." in part:
        return stage_paths.get(part.split(".")[0], "stage")
    return part


def _model_name(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or "gearfmu_drivetrain"
    if s[0].isdigit():
        s = "drivetrain_" + s
    return s[:64]


def load_drivetrain(source: Union[str, Path, Mapping]) -> DrivetrainScene:
    """Parse and validate a drivetrain scene: a path to a TOML file, TOML text (a ``str``
    containing a newline or ``=``) or a mapping of the same structure (stage scene paths are then
    relative to the working directory).  Returns a :class:`DrivetrainScene` in SI; raises
    :class:`SceneError` listing every problem with its key path."""
    source_path: Optional[str] = None
    if isinstance(source, Mapping):
        try:
            text = dumps_toml(source)
        except (TypeError, ValueError) as exc:
            raise SceneError([("<drivetrain>", f"cannot be written as TOML: {exc}")]) from None
    elif isinstance(source, Path) or (isinstance(source, str) and "\n" not in source and "=" not in source):
        path = Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SceneError([("<file>", f"drivetrain file not found: {path}")]) from None
        except (OSError, UnicodeDecodeError) as exc:
            raise SceneError([("<file>", f"cannot read drivetrain file {path}: {exc}")]) from None
        source_path = str(path)
    elif isinstance(source, str):
        text = source
    else:
        raise SceneError([("<drivetrain>", f"expected a path, TOML text or a mapping, got {type(source).__name__}")])
    try:
        data = _toml.loads(text)
    except _toml.TOMLDecodeError as exc:
        raise SceneError([("<toml>", f"not valid TOML: {exc}")], source=source_path or "") from None
    return _build(data, text, source_path)
