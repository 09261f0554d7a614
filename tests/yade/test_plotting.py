"""yade_mpm.plotting on synthetic data: each figure shows what its docstring says it shows."""
import matplotlib
import numpy as np
import pytest

from yade_mpm import plotting, sandpile

SCENE = sandpile.DEFAULT
X_MAX = SCENE.toe_x() + 0.1


def test_pore_pressure_panels_in_time_order_on_a_scale_centred_at_zero(tmp_path):
    """Snapshots given out of order are drawn in time order; the colour scale is diverging about 0
    with the given ends (suction blue, pressure red); the front points (y = 0) are drawn last, on top."""
    rng = np.random.default_rng(1)
    pos = rng.uniform([0, 0, 0], [0.3, 0.1, 0.12], size=(50, 3))
    shots = [("late", 0.6, 0.12, pos, rng.uniform(-50, 900, 50)), ("early", 0.05, 0.03, pos, rng.uniform(-50, 900, 50))]
    path = tmp_path / "p.png"
    fig = plotting.pore_pressure_snapshots(path, shots, SCENE, X_MAX, (-300.0, 1200.0))
    assert path.stat().st_size > 0
    axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert [ax.get_title().split(":")[0] for ax in axes] == ["early", "late"]
    scatter = axes[0].collections[0]
    norm = scatter.norm
    assert isinstance(norm, matplotlib.colors.TwoSlopeNorm) and (norm.vmin, norm.vcenter, norm.vmax) == (-300.0, 0.0, 1200.0)
    # the scatter keeps x and z only: the order is checked through x (y values distinct), the front point last
    assert np.allclose(scatter.get_offsets()[:, 0], pos[np.argsort(-pos[:, 1]), 0])
    assert scatter.get_offsets()[-1, 0] == pos[np.argmin(pos[:, 1]), 0]
    with pytest.raises(ValueError, match="straddle 0"):
        plotting.pore_pressure_snapshots(path, shots, SCENE, X_MAX, (10.0, 1200.0))


def test_velocity_arrows_of_the_slab_only_with_the_fastest_one_the_given_length(tmp_path):
    """Only points in the y slab get an arrow; the quiver's scale maps the largest speed to the given
    plot length (1.5 point spacings in the example)."""
    pos = np.array([[0.1, 0.05, 0.02], [0.2, 0.05, 0.03], [0.15, 0.01, 0.02], [0.25, 0.049, 0.01]])
    vel = np.array([[3e-3, 0, -4e-3], [1e-3, 0, 0], [1.0, 0, 0], [0, 0, 2e-3]])  # the fast one lies outside the slab
    fig = plotting.velocity_field(tmp_path / "v.png", pos, vel, SCENE, X_MAX, (0.04, 0.06), 0.015, "t")
    quiver = next(c for c in fig.axes[0].collections if isinstance(c, matplotlib.quiver.Quiver))
    assert quiver.N == 3
    assert quiver.scale == pytest.approx(5e-3 / 0.015)  # |(3e-3, −4e-3)| = 5e-3 m/s is the fastest in the slab
    with pytest.raises(ValueError, match="slab"):
        plotting.velocity_field(tmp_path / "v.png", pos, vel, SCENE, X_MAX, (0.5, 0.6), 0.015, "t")


def test_plastic_strain_on_start_positions_with_surface_and_circle(tmp_path):
    """κ is drawn at the start positions with its scale up to the 99th percentile; the sliding surface
    and the slip circle are drawn with the data given and labelled."""
    start = np.column_stack([np.linspace(0, 0.3, 101), np.full(101, 0.05), np.linspace(0, 0.1, 101)])
    kappa = np.linspace(0, 1, 101)
    surface = (np.array([0.1, 0.2]), np.array([0.08, 0.0]), "sliding surface")
    circle = (np.array([0.1, 0.15, 0.25]), np.array([0.1, 0.03, 0.0]), "Bishop")
    fig = plotting.plastic_shear_strain(tmp_path / "k.png", start, kappa, SCENE, X_MAX, "t", surface=surface, circle=circle)
    ax = fig.axes[0]
    assert np.allclose(ax.collections[0].get_offsets(), start[:, [0, 2]])
    assert ax.collections[0].norm.vmax == pytest.approx(np.percentile(kappa, 99))
    lines = {line.get_label(): line for line in ax.get_lines()}
    assert np.allclose(lines["sliding surface"].get_ydata(), surface[1]) and np.allclose(lines["Bishop"].get_xdata(), circle[0])


def test_runout_sequence_spreads_its_lines_over_the_run_and_keeps_the_last(tmp_path):
    """Ten profiles, six lines: the first, the last and four between, labelled with their times."""
    x = np.linspace(0, 0.4, 21)
    profiles = [(0.1 * i, x, np.clip(0.12 - (x - 0.1 - 0.002 * i), 0, 0.12)) for i in range(10)]
    fig = plotting.runout_sequence(tmp_path / "r.png", profiles, SCENE, X_MAX)
    labels = [line.get_label() for line in fig.axes[0].get_lines() if line.get_label().startswith("t =")]
    assert len(labels) == 6 and labels[0] == "t = 0.00 s" and labels[-1] == "t = 0.90 s"
    with pytest.raises(ValueError, match="at least one"):
        plotting.runout_sequence(tmp_path / "r.png", [], SCENE, X_MAX)


def test_time_series_panels_carry_the_columns_given(tmp_path):
    """Six panels: head, every probe column, face and toe in mm, kinetic energy on a log axis, water
    in, out and the change of the stored water, and the LEM factors, each series at its own times,
    with None left out (the line joins the evaluated ones)."""
    t = np.linspace(0, 0.7, 8)
    series = {"time_s": t, "head_m": 0.03 + 0.1 * t, "p_upstream_x=0.05_Pa": 100 * t, "p_near_toe_x=0.27_Pa": 50 * t,
              "face_displacement_m": 1e-3 * t, "toe_displacement_m": 5e-4 * t, "kinetic_energy_J": 1e-9 * np.exp(t),
              "injected_kg": 0.01 * t, "removed_kg": 0.008 * t, "stored_kg": 0.3 + 0.002 * t}
    lem = {"all": ([0.0, 0.1, 0.35, 0.7], [1.2, 1.1, 1.0, 0.8]), "deep": ([0.0, 0.35, 0.7], [1.3, None, 0.9])}
    fig = plotting.time_series(tmp_path / "ts.png", series, lem=lem, failure_displacement=1.2e-3, failure_time=0.5)
    head, pressure, displacement, energy, water, safety = fig.axes
    assert np.allclose(head.get_lines()[0].get_ydata(), series["head_m"])
    assert len([ln for ln in pressure.get_lines() if ln.get_label().startswith(("upstream", "near"))]) == 2
    assert np.allclose(displacement.get_lines()[0].get_ydata(), 1e3 * series["face_displacement_m"])
    assert energy.get_yscale() == "log"
    water_lines = {ln.get_label(): ln for ln in water.get_lines()}
    assert np.allclose(water_lines["stored − stored at first record"].get_ydata(), 0.002 * t)
    deep = next(ln for ln in safety.get_lines() if ln.get_label() == "deep")
    assert list(deep.get_xdata()) == [0.0, 0.7] and list(deep.get_ydata()) == [1.3, 0.9]
    shallow = next(ln for ln in safety.get_lines() if ln.get_label() == "all")
    assert list(shallow.get_xdata()) == [0.0, 0.1, 0.35, 0.7]
    assert all(any(len(ln.get_xdata()) == 2 and np.allclose(ln.get_xdata(), 0.5) for ln in ax.get_lines()) for ax in fig.axes)  # the failure mark
