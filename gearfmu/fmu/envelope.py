"""The FMU's envelope record: the operating range an FMU states and checks (docs/fmu.md "Verified envelope").

Both builders write it (``resources/envelope.json``, the validation record, a sentence in the
model description) and hand its checked ranges to the runtime (the kernel's envelope check,
gearkernel.h ``gk_envelope``).  :func:`fmu_envelope_record` makes it from the tables and, when a
model was verified, the plain-data verified envelope of the planner
(:class:`gearfmu.scene.envelope.VerifiedEnvelope` as a dict: its ``kind``, ranges, targets and
worst errors); without one the ranges are the tables' own, "not verified".  Units: pinion torque
N*m, pinion speed rad/s and rpm, temperature degC.
"""
from __future__ import annotations

import json
from typing import Optional, Tuple

import numpy as np

from ..common.units import RPM_TO_RAD_S

__all__ = ["ENVELOPE_FILE", "ENVELOPE_STATUS", "fmu_envelope_record", "runtime_envelope", "envelope_note",
           "envelope_json"]


#: the FMU's machine-readable envelope record (both runtimes), docs/fmu.md "Verified envelope"
ENVELOPE_FILE = "resources/envelope.json"
#: record status by VerifiedEnvelope kind; no (usable) record: "not verified"
ENVELOPE_STATUS = {"plan verification": "verified", "as-written estimate": "estimated"}


def _pair(r):
    return None if r is None else [float(r[0]), float(r[1])]


def fmu_envelope_record(tables, verified: Optional[dict] = None, *,
                        speed_range_rad_s: Optional[Tuple[float, float]] = None) -> dict:
    """The envelope an FMU checks its inputs against and states (``resources/envelope.json``,
    the validation record and the model description; docs/fmu.md "Verified envelope").

    ``verified``: :meth:`gearfmu.scene.envelope.VerifiedEnvelope.to_dict` of the plan or of the as-written estimate;
    None (or an estimate that failed, with an ``error`` key) means "not verified": the ranges
    are then the tables' own -- torque rows, temperature axis -- and ``speed_range_rad_s``
    (the scene's speed range, if any; None: the speed is not checked).  Ranges: pinion torque
    N*m, pinion speed rad/s and rpm, temperature degC (None: that quantity is not checked).
    A verified record without a temperature range (no variation) keeps the tables' axis."""
    torque = np.asarray(tables.torque_Nm, dtype=float)
    axis = tables.temperature_C
    table_temp = [float(np.min(axis)), float(np.max(axis))] if tables.has_temperature_axis else None
    usable = bool(verified) and "error" not in verified and verified.get("kind") in ENVELOPE_STATUS
    if usable:
        status, source = ENVELOPE_STATUS[verified["kind"]], verified["kind"]
        tq = _pair(verified["torque_range_Nm"])
        w = [x * RPM_TO_RAD_S for x in verified["speed_range_rpm"]]
        temp = _pair(verified.get("temperature_range_C")) if table_temp is not None else None
        temp = temp or table_temp
    else:
        status, source = "not verified", "the tables' own range"
        tq = [float(torque.min()), float(torque.max())]
        w = _pair(speed_range_rad_s)
        temp = table_temp
    rec = {
        "format": "gearfmu-envelope", "version": 1, "status": status, "source": source,
        "pinion_torque_range_Nm": tq,
        "pinion_speed_range_rad_s": w,
        "pinion_speed_range_rpm": None if w is None else [x / RPM_TO_RAD_S for x in w],
        "temperature_range_C": temp,
        "speed_margin_rel": 0.1,  # gearkernel.h GK_ENV_SPEED_MARGIN
        "outside": "the FMU logs one fmi2Warning per input (pinion_torque, pinion speed, temperature input) "
                   "the first time the input leaves its range, naming the input, its value and the range, "
                   "and keeps running (the step returns fmi2OK)",
        "verified_envelope": dict(verified) if verified else None,
    }
    if usable:
        for k in ("dte_target_rel", "mesh_force_target_rel", "within_target", "worst_dte_rel",
                  "worst_mesh_force_rel", "worst_at", "fmu_confirmed", "error_definition"):
            rec[k] = verified.get(k)
    return rec


#: gearkernel.h GK_ENV_VERIFIED / _ESTIMATED / _NOT_VERIFIED by record status
_KIND_CODES = {"verified": 0, "estimated": 1, "not verified": 2}


def runtime_envelope(rec: dict) -> dict:
    """What an FMU runtime hands to the kernel's envelope check (gearkernel.h ``gk_envelope``):
    ``kind`` code and the checked ranges in SI (``None``: not checked)."""
    return {"kind": _KIND_CODES[rec["status"]], "pinion_torque_Nm": rec["pinion_torque_range_Nm"],
            "pinion_speed_rad_s": rec["pinion_speed_range_rad_s"], "temperature_C": rec["temperature_range_C"]}


def envelope_note(rec: dict) -> str:
    """One sentence on an FMU's envelope record for its model description."""
    def g(x):
        return "n/a" if x is None else f"{x:.3g}"

    def rng(r, unit):
        return "not checked" if r is None else f"[{r[0]:.6g}, {r[1]:.6g}] {unit}"
    where = (f"pinion torque {rng(rec['pinion_torque_range_Nm'], 'N.m')}, pinion speed "
             f"{rng(rec['pinion_speed_range_rpm'], 'rpm')}, temperature {rng(rec['temperature_range_C'], 'degC')}")
    if rec["status"] == "not verified":
        head = f"Accuracy NOT verified; built for {where} (the tables' own range)"
    else:
        verb = "verified by the fidelity plan" if rec["status"] == "verified" else "estimated (not verified)"
        head = (f"Accuracy {verb} over {where}: worst DTE error {g(rec['worst_dte_rel'])} "
                f"(target {g(rec['dte_target_rel'])}), worst mesh-force error {g(rec['worst_mesh_force_rel'])} "
                f"(target {g(rec['mesh_force_target_rel'])}), relative RMS against the full-fidelity model"
                + ("" if rec.get("fmu_confirmed") is None else
                   f"; FMU check {'confirmed' if rec['fmu_confirmed'] else 'NOT confirmed'}"))
    return head + f". Outside it the FMU warns once per input ({ENVELOPE_FILE})."


def envelope_json(env_rec: dict) -> str:
    """``resources/envelope.json``: the record as JSON (one space indent)."""
    return json.dumps(env_rec, indent=1)
