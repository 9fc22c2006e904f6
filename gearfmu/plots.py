"""PNG plots of tables and simulation results, and of gearboxes: the Campbell diagram and a gearbox run
(matplotlib, no screen needed)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

# A bare Figure renders PNG through matplotlib's Agg canvas without pyplot: no GUI backend is
# chosen or imported, and no global figure manager holds the figures.
from matplotlib.figure import Figure


#: the stiffness axis of the tables plot: (unit, N/m per unit); the label and the plotted values
#: both come from here (1 N/um = 1e6 N/m)
STIFFNESS_UNIT = ("N/um", 1e6)


def _legend_outside(ax) -> None:
    """The legend to the right of the axes, so that it never covers a curve (a helical pair has
    four or more slots)."""
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def tables_figure(tables, *, torque_index: int = 0, max_meshes: int = 6) -> Figure:
    """The figure of :func:`plot_tables` (not saved)."""
    n_show = min(tables.n_phi, int(round(max_meshes * tables.mesh_period_rad / tables.dphi_rad)))
    phi_deg = np.degrees(tables.phi_rad[:n_show])
    k = tables.k_N_per_m[torque_index][:, :n_show]
    e = tables.e_m[torque_index][:, :n_show]
    unit, per = STIFFNESS_UNIT
    fig = Figure(figsize=(10, 9), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for j in range(tables.slots):
        axes[0].plot(phi_deg, k[j] / per, lw=1, label=f"slot {j + 1}")
    axes[0].plot(phi_deg, k.sum(axis=0) / per, "k", lw=1.6, label="total (TVMS)")
    axes[0].set_ylabel(f"stiffness [{unit}]")
    _legend_outside(axes[0])
    axes[0].set_title(f"{tables.provenance.get('scene_name', '')} at "
                      f"T1 = {tables.torque_Nm[torque_index]:.0f} N*m")
    for j in range(tables.slots):
        in_zone = k[j] > 0
        axes[1].plot(phi_deg, np.where(in_zone, e[j] * 1e6, np.nan), lw=1, label=f"slot {j + 1}")
    if tables.e_comprehensive_m is not None:
        axes[1].plot(phi_deg, tables.e_comprehensive_m[torque_index][:n_show] * 1e6, "k--", lw=1.2,
                     label="comprehensive")
    axes[1].set_ylabel("meshing error [um]")
    _legend_outside(axes[1])
    if tables.static_te_m is not None:
        axes[2].plot(phi_deg, tables.static_te_m[torque_index][:n_show] * 1e6, "k")
    axes[2].set_ylabel("loaded static TE [um]")
    axes[2].set_xlabel("pinion angle [deg]")
    for ax in axes:
        ax.grid(alpha=0.3)
    return fig


def plot_tables(tables, path, *, torque_index: int = 0, max_meshes: int = 6) -> Path:
    """TVMS per slot and in total (N/um), per-slot meshing error, comprehensive error
    and loaded static transmission error (um) against pinion angle (deg), over the
    first ``max_meshes`` mesh periods of the table; legends beside the plots."""
    path = Path(path)
    fig = tables_figure(tables, torque_index=torque_index, max_meshes=max_meshes)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def plot_simulation(result, path, *, title: str = "", last_meshes: int | None = None,
                    mesh_period_s: float | None = None) -> Path:
    """DTE, total mesh force, per-pair force and load sharing against time.

    ``result`` needs ``time_s``, ``dte``, ``mesh_force``, ``pair_force`` (n, P)
    and ``load_sharing`` (n, P) (a native SimResult or an FMU run in the same
    shape)."""
    path = Path(path)
    t = np.asarray(result.time_s)
    sel = slice(None)
    if last_meshes and mesh_period_s:
        sel = t >= t[-1] - last_meshes * mesh_period_s
    fig = Figure(figsize=(10, 10))
    axes = fig.subplots(4, 1, sharex=True)
    axes[0].plot(t[sel] * 1e3, np.asarray(result.dte)[sel] * 1e6, "k", lw=1)
    axes[0].set_ylabel("DTE [um]")
    axes[1].plot(t[sel] * 1e3, np.asarray(result.mesh_force)[sel] / 1e3, "k", lw=1)
    axes[1].set_ylabel("mesh force [kN]")
    pf = np.asarray(result.pair_force)
    ls = np.asarray(result.load_sharing)
    for j in range(pf.shape[1]):
        axes[2].plot(t[sel] * 1e3, pf[sel, j] / 1e3, lw=1, label=f"pair slot {j + 1}")
        axes[3].plot(t[sel] * 1e3, ls[sel, j], lw=1, label=f"pair slot {j + 1}")
    axes[2].set_ylabel("pair force [kN]")
    axes[3].set_ylabel("load sharing [1]")
    axes[3].set_xlabel("time [ms]")
    _legend_outside(axes[2])
    for ax in axes:
        ax.grid(alpha=0.3)
    if title:
        axes[0].set_title(title)
    # fixed margins: tight_layout measures every label by drawing the figure once more
    fig.subplots_adjust(left=0.09, right=0.85, bottom=0.05, top=0.96, hspace=0.12)  # legend at the right
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def plot_campbell(campbell: dict, path, *, title: str = "") -> Path:
    """The Campbell diagram of gearfmu.gearbox.modes.campbell: every order as a line through the
    origin (mesh orders solid, shaft orders dotted), every mode as a dashed horizontal line,
    every interference marked, the operating speed as a vertical line; frequency (Hz) against
    the motor speed (rpm)."""
    path = Path(path)
    n_max = campbell["speed_axis_rpm"][1]
    modes = campbell["modes_Hz"]
    f_orders = max([o["hz_per_rpm"] * n_max for o in campbell["orders"]] + [1.0])
    # the frequency axis spans the orders (modes above them cannot meet an order in the speed range)
    f_top = max(1.15 * f_orders, 1.1 * min(modes) if modes else 0.0)
    fig = Figure(figsize=(11, 6.5))
    ax = fig.subplots()
    n = np.array([0.0, n_max])
    for o in campbell["orders"]:
        style = "-" if o["kind"] == "mesh" else ":"
        ax.plot(n, o["hz_per_rpm"] * n, style, lw=1.2 if o["kind"] == "mesh" else 1.0, label=o["name"])
    above = []
    for i, f in enumerate(modes):
        if f > f_top:
            above.append(f"mode {i + 1}: {f:.4g} Hz")
            continue
        ax.axhline(f, color="k", ls="--", lw=0.8)
        ax.text(0.99 * n_max, f, f"mode {i + 1}: {f:.4g} Hz", va="bottom", ha="right", fontsize=8)
    pts = campbell["interferences"]
    if pts:
        ax.plot([p["speed_rpm"] for p in pts], [p["frequency_Hz"] for p in pts], "ro", ms=6, mfc="none",
                label="interference")
    op = campbell.get("operating_speed_rpm")
    if op:
        ax.axvline(op, color="gray", lw=1.5, alpha=0.6, label=f"operating {op:.5g} rpm")
    if above:
        ax.text(0.01, 0.98, "above the axis: " + ", ".join(above), transform=ax.transAxes, va="top", fontsize=8)
    ax.set_xlim(0.0, n_max)
    ax.set_ylim(0.0, f_top)
    ax.set_xlabel("motor (input) speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax.set_title(title)
    fig.subplots_adjust(left=0.08, right=0.74, bottom=0.09, top=0.94)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def plot_gearbox_simulation(result, model, path, *, title: str = "") -> Path:
    """A gearbox run (gearfmu.gearbox.native.GearboxResult): the motor and load speeds (the load
    referred to the motor by the total ratio), every stage's DTE and mesh force, every shaft's
    torque, against time."""
    path = Path(path)
    t = np.asarray(result.time_s) * 1e3
    fig = Figure(figsize=(9, 11))
    axes = fig.subplots(4, 1, sharex=True)
    axes[0].plot(t, result[f"{model.motor}_speed"], lw=1, label=f"{model.motor}")
    axes[0].plot(t, result[f"{model.load}_speed"] / model.load_ratio, lw=1, label=f"{model.load} x total ratio")
    axes[0].set_ylabel("speed [rad/s]")
    for m in model.meshes:
        axes[1].plot(t, result[f"{m.name}.dte"] * 1e6, lw=1, label=m.name)
        axes[2].plot(t, result[f"{m.name}.mesh_force"] / 1e3, lw=1, label=m.name)
    axes[1].set_ylabel("DTE [um]")
    axes[2].set_ylabel("mesh force [kN]")
    for s in model.shafts:
        axes[3].plot(t, result[f"{s.name}.torque"], lw=1, label=s.name)
    axes[3].set_ylabel("shaft torque [N*m]")
    axes[3].set_xlabel("time [ms]")
    for ax in axes:
        ax.grid(alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=8, ncol=3)
    if title:
        axes[0].set_title(title)
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.05, top=0.96, hspace=0.12)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def plot_planetary_simulation(result, model, path, *, title: str = "") -> Path:
    """A run of a drivetrain with planetary stages (gearfmu.planetary.native.PlanetaryResult): the motor
    and load speeds (the load referred to the motor by the total ratio), every mesh's DTE and force,
    every planetary stage's planet load-sharing factors, against time."""
    path = Path(path)
    t = np.asarray(result.time_s) * 1e3
    fig = Figure(figsize=(9, 11))
    axes = fig.subplots(4, 1, sharex=True)
    axes[0].plot(t, result[f"{model.motor}_speed"], lw=1, label=f"{model.motor}")
    axes[0].plot(t, result[f"{model.load}_speed"] / model.load_ratio, lw=1, label=f"{model.load} x total ratio")
    axes[0].set_ylabel("speed [rad/s]")
    for name in model.mesh_names:
        axes[1].plot(t, result[f"{name}.dte"] * 1e6, lw=0.8, label=name)
        axes[2].plot(t, result[f"{name}.mesh_force"] / 1e3, lw=0.8, label=name)
    axes[1].set_ylabel("DTE [um]")
    axes[2].set_ylabel("mesh force [kN]")
    for st in model.stages:
        for n in range(st["planets"]):
            axes[3].plot(t, result[f"{st['name']}.load_sharing_factor[{n + 1}]"], lw=1,
                         label=f"{st['name']} planet {n + 1}")
    axes[3].set_ylabel("load-sharing factor")
    axes[3].set_xlabel("time [ms]")
    for ax in axes:
        ax.grid(alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=7, ncol=4)
    if title:
        axes[0].set_title(title)
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.05, top=0.96, hspace=0.12)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path
