"""The scene file: the single user input of gearfmu (TOML, engineering units), and :func:`load_scene`.

A scene names a spur or helical gear pair (geometry, materials, tooth deviations),
the mesh model (contact model, slices, foundation), the operating envelope, the
table resolution, the solver and the FMU options, and optionally the lubricant,
the roughness and the thermal state.  Every dimensional key carries its unit in
its name (``module_mm``, ``speed_rpm``, ``profile_form_um`` ...).
:func:`load_scene` parses and validates a scene and converts it to SI into the
dataclasses of :mod:`gearfmu.gear.gearpair` and :mod:`gearfmu.scene.options`.
The format, every key (unit, default, range, meaning) and the choices made for
the shipped scenes are documented in ``docs/scene.md``.

Validation
----------
Unknown keys (with the closest valid key as a hint, so ``module_m`` suggests
``module_mm``), wrong types, out-of-range values and inconsistent
combinations are all collected and raised together as one
:class:`SceneError` (a :class:`ValueError`) whose message names the full key
path of every problem, e.g. ``gears.pinion.teeth: must be an integer >= 5,
got 3.5``.  Physically impossible gears (contact ratio < 1, pointed tip,
undercut, interference) are detected by :func:`gearfmu.gear.geometry.pair_geometry`
and re-raised as :class:`SceneError` with the scene key path.  A deprecated
spelling of an option value is accepted with a :class:`FutureWarning` naming the
new one (:data:`gearfmu.common.vocabulary.DEPRECATED_SPELLINGS`).

No pickle, no code execution: a scene is plain TOML data.

The public names of the scene package are importable from here; where each is
defined is listed in :mod:`gearfmu.scene`.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Union

try:  # Python >= 3.11
    import tomllib as _toml
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as _toml  # type: ignore[no-redef]

from ..common.user_files import read_text
from ..common.vocabulary import (CONTACT_MODELS, DAMPING_MODELS, DEFAULT_RUNTIME, INTEGRATORS,
                                 LUBRICATED_CONTACT_MODELS, RUNTIMES)
from ..ehl.lubricant import walther_kinematic_viscosity_cSt
from ..gear.gearpair import GearPairSpec, MeshModelOptions
from . import sections
from .envelope import read_envelope_sections
from .options import (OUTPUT_SAMPLES_PER_MESH, RPM_TO_RAD_S, FmuOptions, Lubricant, OperatingPoint, Scene,
                      SceneError, SolverOptions, TableOptions, ThermalOptions, default_output_interval_s)
from .schema import SCHEMA
from .toml_writer import dumps_toml
from .validate import Reader, check_geometry, sub, thermal_cross_checks

__all__ = [
    "SceneError", "Scene", "OperatingPoint", "TableOptions", "SolverOptions",
    "FmuOptions", "Lubricant", "ThermalOptions", "load_scene", "default_scene_path",
    "dumps_toml", "walther_kinematic_viscosity_cSt", "SCHEMA", "CONTACT_MODELS",
    "DAMPING_MODELS", "INTEGRATORS", "RUNTIMES", "DEFAULT_RUNTIME", "default_output_interval_s",
    "OUTPUT_SAMPLES_PER_MESH",
]


def _model_name(name: str) -> str:
    """The default FMU model name: ``name`` made a C identifier of at most 64 characters."""
    s = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or "gearfmu_scene"
    if s[0].isdigit():
        s = "scene_" + s
    return s[:64]


def _build(data: Dict[str, Any], text: str, source_path: Optional[str]) -> Scene:
    """Check every table of the parsed scene ``data`` and build the :class:`Scene`;
    raise one :class:`SceneError` listing every problem."""
    r = Reader()
    r.table(data, "")
    sc = r.table(sub(data, "scene"), "scene")
    name = sc["name"] if isinstance(sc["name"], str) else "scene"
    shared = r.table(sub(data, "gears"), "gears", required=True)
    mat = r.table(sub(data, "material"), "material")
    r.table(sub(data, "deviations"), "deviations")
    teeth = {}
    for role in ("pinion", "gear"):
        raw = sub(sub(data, "gears"), role)
        t = raw.get("teeth") if isinstance(raw, dict) else None
        teeth[role] = t if isinstance(t, int) and not isinstance(t, bool) and 5 <= t <= 1000 else None
    devs = {role: sections.deviations(r, data, role, teeth[role]) for role in ("pinion", "gear")}
    gears = {role: sections.gear_spec(r, data, role, shared, mat, devs[role]) for role in ("pinion", "gear")}
    mesh_d = r.table(sub(data, "mesh"), "mesh")
    op = r.table(sub(data, "operating"), "operating", required=True)
    tab = r.table(sub(data, "tables"), "tables")
    sol = r.table(sub(data, "solver"), "solver")
    fmu = r.table(sub(data, "fmu"), "fmu")
    roughness = sections.roughness(r, data)
    lub = sections.lubricant(r, data)
    thermal = sections.thermal(r, data)
    envelope, accuracy = read_envelope_sections(r, data, op, source_path)

    # ---------------- cross-key checks (only on values that passed their own checks)
    for k, rk in (("torque_Nm", "torque_range_Nm"), ("speed_rpm", "speed_range_rpm")):
        v, rng = op[k], op[rk]
        if v is not None and rng is not None and not (rng[0] - 1e-12 * abs(rng[1]) <= v <= rng[1] * (1 + 1e-12)):
            scale = SCHEMA["operating"][0].scale if k == "torque_Nm" else RPM_TO_RAD_S
            r.add(f"operating.{k}", f"{v / scale:g} lies outside operating.{rk} "
                                    f"[{rng[0] / scale:g}, {rng[1] / scale:g}]")
    if tab["torque_points"] is not None and tab["torque_points"] > 1 and op["torque_range_Nm"] is None \
            and isinstance(sub(data, "operating"), dict) and "torque_range_Nm" not in data["operating"]:
        r.add("tables.torque_points", f"{tab['torque_points']} torque points need operating.torque_range_Nm")
    if fmu["stop_time_s"] is not None and fmu["output_interval_s"] is not None \
            and fmu["output_interval_s"] > fmu["stop_time_s"]:
        r.add("fmu.output_interval_s", f"must not exceed fmu.stop_time_s ({fmu['stop_time_s']:g} s), "
                                       f"got {fmu['output_interval_s']:g}")
    if mesh_d["contact_model"] in LUBRICATED_CONTACT_MODELS and sub(data, "lubricant") is None:
        r.add("lubricant", f"missing table (required by mesh.contact_model = {mesh_d['contact_model']!r})")
    thermal = thermal_cross_checks(r, thermal, mesh_d["contact_model"], lub)

    pair = None
    if gears["pinion"] is not None and gears["gear"] is not None and shared["backlash_um"] is not None \
            and not ("center_distance_mm" in (sub(data, "gears") or {}) and shared["center_distance_mm"] is None):
        pair = GearPairSpec(pinion=gears["pinion"], gear=gears["gear"], backlash_m=shared["backlash_um"],
                            center_distance_m=shared["center_distance_mm"])
        if not r.problems:
            problem = check_geometry(pair)
            if problem is not None:
                r.add(*problem)
    if r.problems:
        raise SceneError(r.problems, source=source_path or name)

    assert pair is not None
    mesh = MeshModelOptions(contact_model=mesh_d["contact_model"], slices=mesh_d["slices"],
                            foundation=mesh_d["foundation"],
                            shared_foundation_correction=mesh_d["shared_foundation_correction"])
    operating = OperatingPoint(torque_Nm=op["torque_Nm"], speed_rad_s=op["speed_rpm"],
                               torque_range_Nm=op["torque_range_Nm"], speed_range_rad_s=op["speed_range_rpm"],
                               torque_points=tab["torque_points"])
    tables = TableOptions(points_per_mesh=tab["points_per_mesh"], torque_points=tab["torque_points"],
                          slots=tab["slots"])
    solver = SolverOptions(integrator=sol["integrator"], max_step_s=sol["max_step_s"],
                           damping_model=sol["damping_model"])
    dt_auto = fmu["output_interval_s"] is None
    dt = (min(default_output_interval_s(operating.speed_rad_s, pair.pinion.teeth), fmu["stop_time_s"])
          if dt_auto else fmu["output_interval_s"])
    fmu_o = FmuOptions(model_name=fmu["model_name"] or _model_name(name), damping_ratio=fmu["damping_ratio"],
                       runtime=fmu["runtime"], stop_time_s=fmu["stop_time_s"],
                       output_interval_s=dt, output_interval_auto=dt_auto)
    return Scene(name=name, description=sc["description"], text=text, pair=pair, mesh=mesh,
                 operating=operating, tables=tables, solver=solver, fmu=fmu_o, lubricant=lub,
                 source_path=source_path, thermal=thermal, envelope=envelope, accuracy=accuracy,
                 roughness=roughness)


def default_scene_path() -> Path:
    """Path of the package's default scene (``gearfmu/scene/data/default_scene.toml``:
    the gear pair of Zhao et al. 2022 Table 1)."""
    return Path(__file__).resolve().parent / "data" / "default_scene.toml"


def load_scene(source: Union[str, Path, Mapping, None] = None) -> Scene:
    """Parse and validate a scene.

    ``source`` is a path (``str`` or :class:`~pathlib.Path`) to a TOML file,
    TOML text (a ``str`` containing a newline or ``=``), a mapping with the
    same structure (written to TOML first, so the scene keeps a TOML source),
    or None for :func:`default_scene_path`.  Returns a :class:`Scene` in SI;
    raises :class:`SceneError` listing every problem with its key path.
    """
    source_path: Optional[str] = None
    if source is None:
        source = default_scene_path()
    if isinstance(source, Mapping):
        try:
            text = dumps_toml(source)
        except (TypeError, ValueError) as exc:
            raise SceneError([("<scene>", f"cannot be written as TOML: {exc}")]) from None
    elif isinstance(source, Path) or (isinstance(source, str) and "\n" not in source and "=" not in source):
        path = Path(source)
        try:
            text = read_text(path, "a TOML scene")
        except FileNotFoundError:
            raise SceneError([("<file>", f"scene file not found: {path}")]) from None
        except OSError as exc:
            raise SceneError([("<file>", f"cannot read scene file {path}: {exc.strerror or exc}")]) from None
        except ValueError as exc:  # not text: a zip archive, a binary file, not UTF-8
            raise SceneError([("<file>", f"scene file {exc}")]) from None
        source_path = str(path)
    elif isinstance(source, str):
        text = source
    else:
        raise SceneError([("<scene>", f"expected a path, TOML text or a mapping, got {type(source).__name__}")])
    try:
        data = _toml.loads(text)
    except _toml.TOMLDecodeError as exc:
        raise SceneError([("<toml>", f"not valid TOML: {exc}")], source=source_path or "") from None
    return _build(data, text, source_path)
