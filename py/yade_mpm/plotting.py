"""Figures of a sand-pile run (examples/sandpile/sandpile.py, scripts/figures.sh), in the x–z view of
the flume. Each function draws one figure from plain arrays, writes it as PNG and returns the
(closed) matplotlib Figure, so that a live run, a run read back from its HDF5 and CSV files, or a test
on synthetic data all give the same figure. Imports matplotlib (Agg backend) on first use only.
"""
import numpy as np


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return matplotlib, plt


def pile_frame(ax, scene, x_max, title):
    """The flume's x–z frame: the pile's initial outline (dashed), equal axes from x = 0 to `x_max` [m]
    and up to 1.3 pile heights."""
    xs = np.linspace(0, scene.flume_length, 200)
    ax.plot(xs, scene.surface_height(xs), "k--", lw=0.8)
    ax.set_xlim(0, min(scene.flume_length, x_max))
    ax.set_ylim(0, scene.pile_height * 1.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_title(title, fontsize=9)


def pore_pressure_snapshots(path, snapshots, scene, x_max, pressure_range, label="p [Pa] (< 0: suction)"):
    """Pore pressure at the water points at several times, one panel each, in time order.
    `snapshots`: (name, time [s], head [m], positions (N, 3) [m], pressures (N,) [Pa]) tuples;
    `pressure_range`: (p_min < 0, p_max > 0) [Pa] of the diverging colour scale, white at 0. The points
    nearest the viewer (front wall, y = 0) are drawn last."""
    matplotlib, plt = _pyplot()
    p_min, p_max = pressure_range
    if not (p_min < 0 < p_max):
        raise ValueError("pressure_range = %r must straddle 0 (p_min < 0 < p_max) [Pa]" % (pressure_range,))
    ordered = sorted(snapshots, key=lambda s: s[1])
    fig, axes = plt.subplots(len(ordered), 1, figsize=(7, 2.2 * len(ordered)), squeeze=False)
    for ax, (name, t, head, positions, pressures) in zip(axes[:, 0], ordered):
        positions, pressures = np.asarray(positions, dtype=float), np.asarray(pressures, dtype=float)
        order = np.argsort(-positions[:, 1])
        sc = ax.scatter(positions[order, 0], positions[order, 2], c=pressures[order], s=6, cmap="RdYlBu_r",
                        norm=matplotlib.colors.TwoSlopeNorm(vmin=p_min, vcenter=0, vmax=p_max))
        pile_frame(ax, scene, x_max, "%s: t = %.2f s, head %.3f m" % (name, t, head))
        fig.colorbar(sc, ax=ax, label=label)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig


def velocity_field(path, positions, velocities, scene, x_max, slab, arrow_length, title):
    """Solid velocity in the x–z plane as arrows coloured by speed, for the points with `slab[0] ≤ y <
    slab[1]` [m] (a mid-width slab); the fastest arrow is `arrow_length` [m] long on the plot."""
    _, plt = _pyplot()
    positions, velocities = np.asarray(positions, dtype=float), np.asarray(velocities, dtype=float)
    chosen = (positions[:, 1] >= slab[0]) & (positions[:, 1] < slab[1])
    if not chosen.any():
        raise ValueError("no point lies in the slab %r m of y" % (tuple(slab),))
    speed = np.linalg.norm(velocities[chosen], axis=1)
    fig, ax = plt.subplots(figsize=(7, 3))
    q = ax.quiver(positions[chosen, 0], positions[chosen, 2], velocities[chosen, 0], velocities[chosen, 2], speed, cmap="plasma",
                  scale_units="xy", scale=max(speed.max(), 1e-12) / arrow_length, width=0.003)
    fig.colorbar(q, ax=ax, label="|v_s| [m/s]")
    pile_frame(ax, scene, x_max, title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig


def plastic_shear_strain(path, start_positions, kappa, scene, x_max, title, surface=None, circle=None):
    """Plastic shear strain κ of each solid point at its start position (the undeformed pile), the
    colour scale to κ's 99th percentile. `surface`: (x [m], z [m], label) of an extracted sliding
    surface, drawn as a line; `circle`: (x [m], z [m], label) of a limit-equilibrium slip circle."""
    _, plt = _pyplot()
    start_positions, kappa = np.asarray(start_positions, dtype=float), np.asarray(kappa, dtype=float)
    fig, ax = plt.subplots(figsize=(7, 3))
    sc = ax.scatter(start_positions[:, 0], start_positions[:, 2], c=kappa, s=6, cmap="magma_r", vmin=0,
                    vmax=max(float(np.percentile(kappa, 99)), 1e-6))
    fig.colorbar(sc, ax=ax, label="κ, plastic shear strain [-]")
    if surface is not None and len(surface[0]):
        ax.plot(surface[0], surface[1], "c-", lw=2, label=surface[2])
    if circle is not None:
        ax.plot(circle[0], circle[1], "g--", lw=1.5, label=circle[2])
    if (surface is not None and len(surface[0])) or circle is not None:
        ax.legend(fontsize=8, loc="upper right")
    pile_frame(ax, scene, x_max, title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig


def runout_sequence(path, profiles, scene, x_max, count=6):
    """The pile's surface at up to `count` times spread evenly over `profiles` (first and last
    included): (time [s], x [m], height [m], NaN where empty) tuples, e.g. yade_mpm.analysis.deposit_profile
    of each HDF5 frame; the toe's advance reads off the lines' right ends."""
    _, plt = _pyplot()
    if not profiles:
        raise ValueError("runout_sequence needs at least one profile")
    chosen = sorted(set(np.linspace(0, len(profiles) - 1, min(count, len(profiles))).round().astype(int)))
    fig, ax = plt.subplots(figsize=(7, 3))
    colours = plt.cm.viridis(np.linspace(0, 1, len(chosen)))
    for colour, i in zip(colours, chosen):
        t, x, z = profiles[i]
        ax.plot(x, z, "-", color=colour, lw=1.2, label="t = %.2f s" % t)
    ax.legend(fontsize=7, loc="upper right")
    pile_frame(ax, scene, x_max, "pile surface over time (highest solid point per bin)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig


def time_series(path, series, lem=None, failure_displacement=None, failure_time=None):
    """Six panels against time: inflow head; pore pressure at the probes; slope-face and toe
    displacement (and the failure criterion); the solid's kinetic energy (log scale); water injected
    and removed and the change of the water stored; Bishop's factor of safety.
    `series`: columns of the run's time_series.csv as arrays — time_s, head_m, p_<probe>_Pa (any
    number), face_displacement_m, toe_displacement_m, kinetic_energy_J, injected_kg, removed_kg,
    stored_kg. `lem`: {label: (times [s], factors)} of the limit-equilibrium checks, each series at
    its own times (None entries skipped, the line joining the evaluated ones); `failure_time` [s]
    marks every panel."""
    _, plt = _pyplot()
    t = np.asarray(series["time_s"], dtype=float)
    fig, axes = plt.subplots(6, 1, figsize=(7, 13), sharex=True)
    head, pressure, displacement, energy, water, safety = axes
    head.plot(t, series["head_m"])
    head.set_ylabel("inflow head H [m]")
    for key in series:
        if key.startswith("p_") and key.endswith("_Pa"):
            pressure.plot(t, series[key], label=key[2:-3].replace("_", " "))
    pressure.set_ylabel("pore pressure [Pa]")
    pressure.legend(fontsize=7)
    displacement.plot(t, 1e3 * np.asarray(series["face_displacement_m"]), label="lower slope face (mean |u|)")
    displacement.plot(t, 1e3 * np.asarray(series["toe_displacement_m"]), label="toe region (mean u_x)")
    if failure_displacement is not None:
        displacement.axhline(1e3 * failure_displacement, color="r", ls=":", label="failure criterion")
    displacement.set_ylabel("displacement [mm]")
    displacement.legend(fontsize=7)
    kinetic = np.asarray(series["kinetic_energy_J"], dtype=float)
    energy.semilogy(t, np.where(kinetic > 0, kinetic, np.nan))
    energy.set_ylabel("solid kinetic energy [J]")
    stored = np.asarray(series["stored_kg"], dtype=float)
    water.plot(t, series["injected_kg"], label="injected (inflow face)")
    water.plot(t, series["removed_kg"], label="removed (faces, cloth)")
    water.plot(t, stored - stored[0], label="stored − stored at first record")
    water.set_ylabel("water [kg]")
    water.legend(fontsize=7)
    if lem is not None:
        styles = ("o-", "s--", "^:", "d-.")
        for i, (label, (lem_times, values)) in enumerate(lem.items()):
            values = np.array([np.nan if v is None else v for v in values], dtype=float)
            evaluated = np.isfinite(values)
            safety.plot(np.asarray(lem_times, dtype=float)[evaluated], values[evaluated], styles[i % len(styles)], ms=3, label=label)
        safety.legend(fontsize=7)
    safety.axhline(1, color="k", lw=0.8)
    safety.set_ylabel("LEM factor of safety [-]")
    safety.set_xlabel("t [s]")
    if failure_time is not None:
        for ax in axes:
            ax.axvline(failure_time, color="r", lw=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return fig
