"""PNG plots of tables and simulation results (matplotlib, no screen needed)."""
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
