"""The drives of driven members of planetary stages (docs/planetary.md "Driven members"): each drive's
rigid motion -- every DOF's speed per unit drive speed with the motor DOF at rest --, and a translational
stage whose carrier a drive turns: its frame turning with the drive too, its elements reading rotations
relative to that frame.  Used by gearfmu.planetary.model.build_drivetrain on its DOFs and elements
(springs: (name, kind, [(DOF, coefficient)], k, c, frame ratio); mesh rows: dicts with their x map)."""
from __future__ import annotations

import numpy as np

__all__ = ["drive_modes"]


def _rigid_motion(A, free, d, n) -> np.ndarray:
    """The velocities (every DOF) with DOF d at 1, DOF 0 and the DOFs not in ``free`` at 0 that leave the
    elements (unit rows of A) undeflected, by least squares (the caller checks the residual A v)."""
    v = np.zeros(n)
    v[d] = 1.0
    sol, *_ = np.linalg.lstsq(A[:, free], -A[:, d], rcond=None)
    v[free] = sol
    return v


def _element_rows(n: int, springs, mesh_rows) -> np.ndarray:
    """The elements' maps (springs, then meshes) as unit rows over the n DOFs."""
    rows = [ent for _, _, ent, _, _, _ in springs] + [r["x"] for r in mesh_rows]
    A = np.zeros((len(rows), n))
    for k, ent in enumerate(rows):
        for dof, cf in ent:
            A[k, dof] += cf
        A[k] /= max(float(np.linalg.norm(A[k])), 1e-300)
    return A


def drive_modes(planetaries, stage_info, names, kind, springs, mesh_rows, frames, *, error=ValueError):
    """(the drives of the driven members, per frame (drive DOF or -1, its ratio)): each drive's rigid
    motion (every DOF's speed per unit drive speed with the motor DOF and the other drives at rest: the
    velocities that leave every spring and mesh undeflected, by least squares on the elements' unit maps,
    checked exact to 1e-9).  A translational stage measures its translations and its elements' rotations
    in the frame that turns with its carrier: a drive that turns the carrier (h_c != 0) turns the frame
    too (at g_c omega + h_c q_d'), and every element of the stage that reads rotations takes the drive's
    part off them (an entry -h_c sum(rotation coefficients) on the drive DOF), so that the rigid motion
    leaves the translations at rest (docs/planetary.md "Driven members").  ``springs`` and ``mesh_rows``
    are completed in place; ``names``, ``kind``: the DOFs' names and kinds; ``error``: the model's error
    class."""
    drives = [(i, st, si) for i, (st, si) in enumerate(zip(planetaries, stage_info)) if "drive" in si["dofs"]]
    frame_drive = [(-1, 0.0)] * len(frames)
    if not drives:
        return [], frame_drive
    n = len(names)
    ddofs = [si["dofs"]["drive"] for _, _, si in drives]
    free = [i for i in range(1, n) if i not in ddofs]
    A = _element_rows(n, springs, mesh_rows)
    modes = [_rigid_motion(A, free, si["dofs"]["drive"], n) for _, _, si in drives]
    for j2, (st2, si2) in enumerate(zip(planetaries, stage_info)):
        if st2.model != "translational":
            continue
        dc = si2["dofs"]["carrier"]
        turning = [(j, float(v[dc])) for j, v in enumerate(modes) if abs(float(v[dc])) > 1e-13 * float(np.max(np.abs(v)))]
        if len(turning) > 1:
            i, st, _ = drives[turning[1][0]]
            raise error(f"planetary[{i}] ({st.name}).driven_speed_rad_s: the carrier of the translational "
                                      f"stage {st2.name!r} is turned by two drives; its frame follows one")
        if turning:
            _frame_follows_drive(si2, kind, springs, mesh_rows, frames, frame_drive, ddofs[turning[0][0]],
                                 turning[0][1])
    A = _element_rows(n, springs, mesh_rows)
    out = []
    for i, st, si in drives:
        d = si["dofs"]["drive"]
        v = _rigid_motion(A, free, d, n)
        if float(np.max(np.abs(A @ v))) > 1e-9:
            raise error(f"planetary[{i}] ({st.name}).driven_speed_rad_s: the drive of the {st.held} has "
                                      "no rigid motion in this drivetrain (its elements would deflect)")
        v[np.abs(v) <= 1e-13 * float(np.max(np.abs(v)))] = 0.0
        v[si["dofs"][st.held]] = 1.0   # the member turns with its drive (exact; the solve rounds at 1e-15)
        out.append({"port": st.port(st.held), "dof": int(d), "stage": st.name, "speed_rad_s":
                    float(st.driven_speed_rad_s), "mode": v})
    return out, frame_drive


def _frame_follows_drive(si, kind, springs, mesh_rows, frames, frame_drive, d: int, hc: float) -> None:
    """The frames of the translational stage ``si`` turn with drive DOF d at ratio hc too; its elements that
    read rotations in that frame get the entry -hc sum(rotation coefficients) on d."""
    frame_dofs = set(si["dofs"]["planet_zeta"]) | set(si["dofs"]["planet_eta"])
    for p in ("sun", "ring", "carrier"):
        frame_dofs.update(si["dofs"].get(p + "_xy", ()))
    for r, f in enumerate(frames):
        if f[0] in frame_dofs:
            frame_drive[r] = (d, hc)

    def relative(ent):
        rot = sum(cf for dof, cf in ent if kind[dof] == "rot")
        return ent + [(d, -hc * rot)] if rot != 0.0 and any(dof in frame_dofs for dof, _ in ent) else ent

    for k, (name, what, ent, kk, c, gf) in enumerate(springs):
        springs[k] = (name, what, relative(list(ent)), kk, c, gf)
    for m in si["meshes"]:
        mesh_rows[m]["x"] = relative(list(mesh_rows[m]["x"]))
