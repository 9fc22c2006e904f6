"""FMU against the native solver: run both on the same inputs and steps, compare.

The FMU is driven by fmpy (``simulate_fmu`` with ``output_interval`` equal to
the communication step); the native solver by :func:`gearfmu.dynamics.native.simulate`
with the same communication step and the same internal step bound, so both
take identical RK4 substeps and should agree to round-off.
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from ..common.user_files import ArchiveError, archive_kind, read_archive
from ..common.progress import progress_bar, reporting_enabled, ticking
from ..common.settings import RunSettings
from ..common.vocabulary import INTEGRATORS
from ..dynamics.native import simulate
from .integrity import RECORDS, integrity_problem, platform_problem
from .modeldesc import expand_variables, features_of, load_spec

#: default agreement criterion of ``gearfmu validate``: largest |FMU - native| of every output
#: relative to the native signal's range (the FMU and the native solver take the same RK4 substeps)
DEFAULT_TOLERANCE = 1e-9


class FmuMismatchError(ValueError):
    """The FMU cannot be compared with the scene: not an FMU, built from another scene or other
    tables, or another slot count / variable set.  The message names the file and the reason."""


class FmuRunError(ValueError):
    """fmpy could not load or run the FMU (its binary does not load here, it refused to
    instantiate or a step failed); the message names the file and fmpy's reason."""


SCALAR_OUTPUTS = ("pinion_speed", "gear_speed", "pinion_angle", "gear_angle", "dte",
                  "mesh_force", "mesh_stiffness")


def output_names(slots: int) -> List[str]:
    """The FMU's output variable names for P slots (the naming contract)."""
    names = list(SCALAR_OUTPUTS)
    names += [f"pair_force[{i + 1}]" for i in range(slots)]
    names += [f"load_sharing[{i + 1}]" for i in range(slots)]
    return names


def output_units(slots: int) -> Dict[str, str]:
    """The unit of every output of :func:`output_names` (the FMU's, from
    modeldescription/variables.toml; "1" for a dimensionless one)."""
    units = {v.name: v.unit or "1" for v in expand_variables(load_spec(), slots)}
    return {n: units[n] for n in output_names(slots)}


def native_columns(result, slots: int) -> Dict[str, np.ndarray]:
    """Native SimResult arrays keyed by FMU output names."""
    cols = {n: np.asarray(getattr(result, n)) for n in SCALAR_OUTPUTS}
    pf = np.asarray(result.pair_force)
    ls = np.asarray(result.load_sharing)
    for i in range(slots):
        cols[f"pair_force[{i + 1}]"] = pf[:, i]
        cols[f"load_sharing[{i + 1}]"] = ls[:, i]
    return cols


#: where an FMU carries its validation record (gearfmu.fmu.standalone_build.validation_record)
_RECORD = "resources/validation/record.json"
_RECORD_SCENE = "resources/validation/scene.toml"


@dataclass
class FmuFile:
    """An FMU file opened for reading: its model description (fmpy), its validation
    record (None when it carries none) and the scene text it was built from (or None)."""
    path: Path
    model_description: object
    record: Optional[dict]
    scene_text: Optional[str]

    @property
    def variable_names(self) -> List[str]:
        """The variables by their FMI 2 names: an FMI 3 array ``pair_force`` of P elements is
        ``pair_force[1]`` .. ``pair_force[P]``; FMI 3's independent ``time`` is left out."""
        out = []
        for v in self.model_description.modelVariables:
            if v.causality == "independent":
                continue
            shape = getattr(v, "shape", None)
            out += [f"{v.name}[{i + 1}]" for i in range(int(shape[0]))] if shape else [v.name]
        return out


def open_fmu(path) -> FmuFile:
    """Open ``path`` as an FMU to run here; FmuMismatchError naming the file and what is wrong
    otherwise: missing, a directory, empty, not a zip archive (an SSP package or a table file is
    called by its name), a damaged archive (truncated; a member failing its CRC-32, cut short or
    not decompressible), no or unreadable modelDescription.xml, not Co-Simulation, a member
    that does not match the SHA-256 the FMU recorded at build time or a GUID that is not its
    own (:mod:`gearfmu.fmu.integrity`), no binary for this platform."""
    from fmpy import read_model_description  # fmpy: heavy, only to read an FMU

    p = Path(path)
    try:
        arc = read_archive(p, "FMU", keep=(_RECORD, _RECORD_SCENE) + RECORDS)
    except ArchiveError as exc:
        raise FmuMismatchError(str(exc)) from None
    if "modelDescription.xml" not in arc.names:
        kind = archive_kind(arc.names)
        if kind == "an SSP package":
            inner = [n for n in arc.names if n.lower().endswith(".fmu")]
            raise FmuMismatchError(f"{p}: an SSP package, not an FMU; the FMU inside it is "
                                   f"{', '.join(inner) or '(none)'}: extract it and give that")
        raise FmuMismatchError(f"{p}: {kind}, not an FMU (no modelDescription.xml in the archive)"
                               if kind else f"{p}: not an FMU (no modelDescription.xml in the archive)")
    try:
        record = json.loads(arc.data[_RECORD].decode("utf-8")) if _RECORD in arc.data else None
        scene = arc.data[_RECORD_SCENE].decode("utf-8") if _RECORD_SCENE in arc.data else None
    except ValueError as exc:  # not UTF-8, not JSON
        raise FmuMismatchError(f"{p}: altered FMU: its validation record cannot be read ({exc})") from None
    try:
        md = read_model_description(str(p))
    except Exception as exc:  # noqa: BLE001 - fmpy raises plain exceptions for invalid XML
        raise FmuMismatchError(f"{p}: modelDescription.xml cannot be read ({_first_line(exc)})") from None
    if getattr(md, "coSimulation", None) is None:
        raise FmuMismatchError(f"{p}: not a Co-Simulation FMU (no <CoSimulation> in modelDescription.xml)")
    problem = integrity_problem(arc, md) or platform_problem(arc.names, md)
    if problem:
        raise FmuMismatchError(f"{p}: {problem}")
    return FmuFile(p, md, record if isinstance(record, dict) else None, scene)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _scene_name(text: Optional[str]) -> str:
    try:
        data = tomllib.loads(text or "")
        return repr(str((data.get("scene") or data.get("drivetrain"))["name"]))   # a pair or a drivetrain scene
    except Exception:  # noqa: BLE001 - a scene without a readable name
        return "(unnamed)"


def check_fmu_matches(fmu: FmuFile, *, scene_text: Optional[str] = None, scene_label: str = "SCENE",
                      tables=None) -> None:
    """Refuse (FmuMismatchError, naming both) an FMU whose validation record names another scene
    than ``scene_text`` or other tables than ``tables`` (SHA-256 of the table arrays), or whose
    variables are not those of ``tables`` (slot count, temperature input).  Checks only what is
    given; nothing is simulated."""
    rec = fmu.record or {}
    want_sha = rec.get("scene_sha256")
    if scene_text is not None and want_sha is not None:
        have_sha = hashlib.sha256(scene_text.encode()).hexdigest()
        if have_sha != want_sha:
            built, given = _scene_name(fmu.scene_text), _scene_name(scene_text)
            same = " (the same name, other contents: the scene changed since the build)" if built == given else ""
            raise FmuMismatchError(
                f"{fmu.path} was built from scene {built} (sha256 {want_sha[:12]}), not from {scene_label} "
                f"{given} (sha256 {have_sha[:12]}){same}; give the scene the FMU was built from "
                "or build the FMU from this scene")
    if tables is None:
        return
    trec = rec.get("tables")
    tsha = trec.get("tables_bin_sha256") if isinstance(trec, dict) else None
    if tsha is not None:
        have = hashlib.sha256(tables.to_bytes()[1]).hexdigest()
        if have != tsha:
            raise FmuMismatchError(
                f"{fmu.path} carries other tables (sha256 {tsha[:12]}) than {scene_label} gives "
                f"(sha256 {have[:12]}); it was built from other tables (e.g. build --tables) or another "
                "version of gearfmu")

    have = fmu.variable_names
    # Model Exchange's variables (docs/standalone.md "Model Exchange"), as far as the FMU has them
    me = tuple(f for f, name in (("model_exchange", "dte_rate"), ("zone_events", "zone_indicator[1]"),
                                 ("node_events", "segment_indicator_low")) if name in have)
    want = [v.name for v in expand_variables(load_spec(), tables.slots, features_of(tables) + me)]
    if set(want) != set(have):
        fmu_slots = sum(1 for n in have if n.startswith("pair_force["))
        extra, missing = sorted(set(have) - set(want)), sorted(set(want) - set(have))
        raise FmuMismatchError(
            f"{fmu.path} has {fmu_slots} pair slots and other variables than {scene_label}'s tables "
            f"({tables.slots} slots): only in the FMU {extra[:6]}{' ...' if len(extra) > 6 else ''}, "
            f"missing from it {missing[:6]}{' ...' if len(missing) > 6 else ''}")


class _LogTee(io.TextIOBase):
    """Passes what fmpy prints (the FMU's log: "[ERROR] message") through to ``out`` and keeps
    the last error or fatal message, to name it when the run fails."""

    def __init__(self, out):
        self.out, self._last = out, None

    def write(self, s):
        for line in s.splitlines():
            if line.startswith(("[ERROR] ", "[FATAL] ")):
                self._last = line.split("] ", 1)[1].strip()
        return self.out.write(s)

    def flush(self):
        self.out.flush()

    def last_error(self) -> Optional[str]:
        return self._last


@dataclass
class FmuRun:
    time_s: np.ndarray
    columns: Dict[str, np.ndarray]
    wall_s: float


def run_fmu(fmu_path, *, stop_time_s: float, comm_step_s: float, start_values=None,
            names=None) -> FmuRun:
    """Simulate an FMU with fmpy at a fixed communication step; FmuRunError naming the file when
    fmpy cannot load or run it."""
    import fmpy  # fmpy: heavy, only to run an FMU

    log = _LogTee(sys.stdout)
    bar = None
    try:
        fmi3 = fmpy.read_model_description(str(fmu_path)).fmiVersion.startswith("3")
        if fmi3 and names is not None:  # FMI 3: the elements pair_force[i] are the array pair_force
            names = list(dict.fromkeys(n.split("[", 1)[0] for n in names))
        steps = max(1, int(round(stop_time_s / comm_step_s)))
        bar = progress_bar(desc=f"gearfmu: {Path(fmu_path).name} through fmpy", enabled=reporting_enabled(),
                           total=steps, unit="step", leave=False)

        def step_finished(time_s, recorder):  # fmpy calls it after every communication step
            bar.update(1)
            return True

        t0 = time.perf_counter()
        with contextlib.redirect_stdout(log):
            res = fmpy.simulate_fmu(str(fmu_path), stop_time=stop_time_s, output_interval=comm_step_s,
                                    start_values=dict(start_values or {}), output=names,
                                    step_finished=step_finished if not bar.disable else None)
    except Exception as exc:  # noqa: BLE001 - fmpy raises Exception, FMICallException, OSError (loader)
        said = log.last_error()
        raise FmuRunError(f"{fmu_path}: fmpy could not run the FMU ({_first_line(exc)}"
                          + (f"; the FMU logged: {said})" if said else ")")) from exc
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - t0
    cols = {}
    for n in res.dtype.names:
        a = np.asarray(res[n], dtype=float)
        if a.ndim == 2:  # an FMI 3 array: one column per element, named as in FMI 2
            cols.update({f"{n}[{i + 1}]": a[:, i] for i in range(a.shape[1])})
        elif n != "time":
            cols[n] = a
    return FmuRun(np.asarray(res["time"], dtype=float), cols, wall)


def diff_report(ref: Dict[str, np.ndarray], other: Dict[str, np.ndarray]) -> Dict[str, dict]:
    """Per output: largest and RMS absolute difference, the reference's range,
    and the largest difference relative to that range.  Both must hold the same
    outputs with the same number of samples (FmuMismatchError otherwise: never a
    partial comparison)."""
    if set(ref) != set(other):
        raise FmuMismatchError(f"outputs differ: only in the reference {sorted(set(ref) - set(other))}, "
                               f"only in the other run {sorted(set(other) - set(ref))}")
    out = {}
    for name, a in ref.items():
        b = other[name]
        if len(a) != len(b):
            raise FmuMismatchError(f"{name}: {len(a)} samples in the reference, {len(b)} in the other run")
        n = len(a)
        d = np.abs(a[:n] - b[:n])
        rng = float(np.ptp(a[:n])) if n else 0.0
        scale = rng if rng > 0 else max(float(np.max(np.abs(a[:n]))) if n else 0.0, 1e-300)
        out[name] = {
            "max_abs_diff": float(d.max()) if n else 0.0,
            "rms_diff": float(np.sqrt(np.mean(d ** 2))) if n else 0.0,
            "range": rng,
            "rel_max_diff": float(d.max() / scale) if n else 0.0,
        }
    return out


def fmu_integrator(fmu_path, start_values=None):
    """Name of the integrator an FMU runs with ('rk4', 'rk4_kink', 'rk4_node', 'rk4_seg'): its parameter
    ``integrator`` (docs/model.md; code 0/1) from ``start_values`` or else the start
    value in its modelDescription.xml; None if the FMU has no such parameter."""
    from fmpy import read_model_description  # fmpy: heavy, only to read an FMU


    if start_values and "integrator" in start_values:
        code = int(start_values["integrator"])
    else:
        md = read_model_description(str(fmu_path))
        var = next((v for v in md.modelVariables if v.name == "integrator"), None)
        if var is None or var.start is None:
            return None
        code = int(var.start)
    return {v: k for k, v in INTEGRATORS.items()}.get(code)


def validate_fmu_against_native(fmu_path, tables, settings: Optional[RunSettings] = None, *,
                                native_kwargs: Optional[dict] = None, stop_time_s: float, comm_step_s: float,
                                start_values=None, tolerance: float = DEFAULT_TOLERANCE,
                                scene_text: Optional[str] = None) -> dict:
    """The report of ``gearfmu validate``: fmpy validation problems, per-output
    differences (FMU minus native), wall time of each, and ``failed``: the outputs
    whose largest difference exceeds ``tolerance`` (1) of the native signal's range.
    The native run: :func:`gearfmu.dynamics.native.simulate` with ``settings`` (the run settings
    the FMU was built with, :class:`gearfmu.common.settings.RunSettings`) and ``native_kwargs``
    (its keyword arguments, replacing fields), over ``stop_time_s`` in steps of ``comm_step_s``.
    Without ``integrator`` in ``native_kwargs`` the native run uses the FMU's own
    (:func:`fmu_integrator`).  Before anything runs, :func:`check_fmu_matches` refuses
    an FMU of another scene (``scene_text`` when given), other tables or another
    slot count / variable set (FmuMismatchError)."""
    from fmpy.validation import validate_fmu  # fmpy: heavy, only to validate an FMU

    native_kwargs = dict(native_kwargs or {})
    if not (tolerance >= 0 and tolerance < float("inf")):
        raise FmuMismatchError(f"tolerance: must be finite and >= 0, got {tolerance!r}")
    check_fmu_matches(open_fmu(fmu_path), scene_text=scene_text, tables=tables)
    with ticking(f"checking {Path(fmu_path).name} with fmpy's validation"):
        problems = [str(p) for p in validate_fmu(str(fmu_path))]
    if "integrator" not in native_kwargs:
        integ = fmu_integrator(fmu_path, start_values)
        if integ is not None:
            native_kwargs["integrator"] = integ
    names = output_names(tables.slots)
    fmu = run_fmu(fmu_path, stop_time_s=stop_time_s, comm_step_s=comm_step_s,
                  start_values=start_values, names=names)
    simulate(tables, settings, **dict(native_kwargs, stop_time_s=min(stop_time_s, 10 * comm_step_s),
                                      comm_step_s=comm_step_s))  # JIT warm-up, not timed
    with ticking(f"native solver over {stop_time_s:g} s"):
        t0 = time.perf_counter()
        nat = simulate(tables, settings, **dict(native_kwargs, stop_time_s=stop_time_s, comm_step_s=comm_step_s))
        native_wall = time.perf_counter() - t0
    per = diff_report(native_columns(nat, tables.slots), fmu.columns)
    return {
        "fmu": str(fmu_path),
        "fmpy_problems": problems,
        "stop_time_s": stop_time_s,
        "comm_step_s": comm_step_s,
        "max_step_s": native_kwargs.get("max_step_s", None if settings is None else settings.max_step_s),
        "samples": int(len(fmu.time_s)),
        "outputs": per,
        "max_abs_diff": {k: v["max_abs_diff"] for k, v in per.items()},
        "rms_diff": {k: v["rms_diff"] for k, v in per.items()},
        "max_rel_diff": max((v["rel_max_diff"] for v in per.values()), default=0.0),
        "tolerance": tolerance,
        "failed": {k: v["rel_max_diff"] for k, v in per.items() if not v["rel_max_diff"] <= tolerance},
        "native_wall_s": native_wall,
        "fmu_wall_s": fmu.wall_s,
    }
