"""Steady seepage of a saturated 2D section whose surface holds suction, computed independently of the
MPM (numpy): the reference the sand pile's pore pressure is measured against (doc/sandpile.md, "Pore
pressure against steady seepage").

The section is {0 ≤ x ≤ length, 0 ≤ z ≤ surface(x)}, saturated throughout, Darcy flow with a uniform
conductivity: the total head h = z + p/γw is harmonic. Boundaries, as the sand-pile example sets them:
the inflow face x = 0 holds the reservoir's head H below its level and is a capillary surface above it;
the base is impermeable; the rest of the surface is a capillary surface (theory.md eq. 8.5e), i.e. the
Signorini conditions of a seepage face: p ≤ 0 (h ≤ z), no flux where p < 0, outflow where p = 0. Optionally
the face x = length holds a uniform head instead (a slab between two reservoirs).

Discretisation: conservative finite volumes on the dual cells of a square node grid, cut by the section
(a link between two nodes carries the part of their shared cell face that lies inside: half along the
base, the faces and a surface on a node plane, the cut part where the slope crosses it), solved by
projected successive over-relaxation (the obstacle problem: each sweep clamps the surface nodes — those
with a neighbour outside, and the faces' nodes off the reservoir — to h ≤ z), red-black ordered so that a
sweep is two numpy passes. The surface condition is applied at those nodes, up to a spacing inside the
true surface: first order in the spacing near the slope. (A mirror of the missing neighbour, second order on
a node plane, is not conservative at a staircase's steps and converged to other heads on the pile's slope:
60 Pa for 67 Pa upstream at H = 0.03 m.)"""
import argparse
import json
import math
import os

import numpy as np


_LINKS = ((1, 0), (-1, 0), (0, 1), (0, -1))  # a node's neighbours (Δi, Δj), in the order of its link weights


def _shifted(a, di, dj):
    """a's value at (i + di, j + dj) for every node (i, j); zero (False) beyond the grid."""
    out = np.zeros_like(a)
    out[max(-di, 0):a.shape[0] - max(di, 0), max(-dj, 0):a.shape[1] - max(dj, 0)] = a[max(di, 0):a.shape[0] + min(di, 0) or None,
                                                                                      max(dj, 0):a.shape[1] + min(dj, 0) or None]
    return out


class SteadySeepage:
    """The steady head on a grid of `spacing` [m]; see the module's docstring for the problem.

    surface: callable z_s(x) [m] (numpy-vectorised), the section's top; length, height: its extent [m];
    inflow_head: H [m], the reservoir's level at x = 0 (0 ≤ H); outflow_head: a uniform head [m] held on
    the face x = length, or None (that face, if any, is part of the capillary surface)."""

    def __init__(self, surface, length, height, inflow_head, spacing, outflow_head=None, tolerance=1e-12, max_sweeps=400000):
        for name, value, low in (("length", length, 0), ("height", height, 0), ("spacing", spacing, 0)):
            if not value > low:
                raise ValueError("%s = %r m is outside the valid range (0, inf)" % (name, value))
        if not 0 <= inflow_head:
            raise ValueError("inflow_head = %r m is outside the valid range [0, inf)" % inflow_head)
        if spacing > min(length, height) / 4:
            raise ValueError("spacing = %r m is outside the valid range (0, %g] (four cells across the section)" % (spacing, min(length, height) / 4))
        self.spacing = float(spacing)
        nx, nz = int(round(length / spacing)), int(round(height / spacing))
        self.nx, self.nz = nx, nz
        x, z = np.arange(nx + 1) * spacing, np.arange(nz + 1) * spacing
        X, Z = np.meshgrid(x, z, indexing="ij")
        inside = Z <= np.asarray(surface(X), dtype=float) + 1e-12
        self.inside = inside

        east, west, north = _shifted(inside, 1, 0), _shifted(inside, -1, 0), _shifted(inside, 0, 1)
        fixed = inside & (X == 0) & (Z < inflow_head - 1e-12)
        if outflow_head is not None:
            fixed |= inside & (np.arange(nx + 1)[:, None] == nx)
        on_face = (np.arange(nx + 1)[:, None] == 0) | ((np.arange(nx + 1)[:, None] == nx) & (outflow_head is None))
        obstacle = inside & ~fixed & (on_face | ~west | ~east | ~north)
        self.fixed, self.obstacle = fixed, obstacle
        # cut-cell weights: a link carries the part of its dual-cell face that lies inside the section
        # (the base, the faces x = 0 and x = length and the surface cut it), relative to a whole face
        x_mid = (np.arange(nx) + 0.5) * spacing  # the faces between columns i and i + 1
        s_mid = np.asarray(surface(x_mid), dtype=float)[:, None]
        lower, upper = np.maximum(z - 0.5 * spacing, 0)[None, :], (z + 0.5 * spacing)[None, :]
        east_link = np.clip(np.minimum(s_mid, upper) - lower, 0, None) / spacing * (inside[:-1, :] & inside[1:, :])
        samples = (np.arange(16) + 0.5) / 16  # across a face between rows j and j + 1, per column
        across = x[:, None] + (samples[None, :] - 0.5) * spacing
        span = (across >= 0) & (across <= length)
        s_across = np.asarray(surface(np.clip(across, 0, length)), dtype=float)
        z_mid = (np.arange(nz) + 0.5) * spacing
        north_link = (span[:, :, None] * (s_across[:, :, None] >= z_mid[None, None, :])).mean(axis=1) * (inside[:, :-1] & inside[:, 1:])
        w_east, w_west, w_north, w_south = (np.zeros((nx + 1, nz + 1)) for _ in range(4))
        w_east[:-1, :], w_west[1:, :] = east_link, east_link
        w_north[:, :-1], w_south[:, 1:] = north_link, north_link
        weights = [w_east, w_west, w_north, w_south]
        self._weights = weights
        total = sum(weights)
        free = inside & ~fixed & (total > 0)
        head = np.where(inside, inflow_head, 0.0)
        if outflow_head is not None:
            head[-1, :] = np.where(inside[-1, :], outflow_head, 0.0)
        head = np.where(obstacle, np.minimum(head, Z), head)
        colour = np.add.outer(np.arange(nx + 1), np.arange(nz + 1)) % 2
        omega = 2 / (1 + math.sin(math.pi / max(nx, nz)))
        self.sweeps = 0
        for sweep in range(max_sweeps):
            change = 0.0
            for c in (0, 1):
                mask = free & (colour == c)
                mean = sum(w * _shifted(head, di, dj) for w, (di, dj) in zip(weights, _LINKS)) / np.where(total > 0, total, 1)
                new = head + omega * (mean - head)
                new = np.where(obstacle, np.minimum(new, Z), new)
                if mask.any():
                    change = max(change, float(np.abs(new - head)[mask].max()))
                head = np.where(mask, new, head)
            self.sweeps = sweep + 1
            if change < tolerance:
                break
        else:
            raise RuntimeError("steady seepage: no convergence in %d sweeps (change %.3g m)" % (max_sweeps, change))
        self.head = head

    def head_at(self, x, z):
        """Total head [m] at (x, z) [m], bilinear between the nodes (arrays broadcast)."""
        fi = np.clip(np.asarray(x, dtype=float) / self.spacing, 0, self.nx - 1e-9)
        fj = np.clip(np.asarray(z, dtype=float) / self.spacing, 0, self.nz - 1e-9)
        i, j = np.minimum(fi.astype(int), self.nx - 1), np.minimum(fj.astype(int), self.nz - 1)
        a, b = fi - i, fj - j
        h = self.head
        return (1 - a) * (1 - b) * h[i, j] + a * (1 - b) * h[i + 1, j] + (1 - a) * b * h[i, j + 1] + a * b * h[i + 1, j + 1]

    def pressure_at(self, x, z, unit_weight):
        """Pore pressure γw (h − z) [Pa] at (x, z), unit_weight γw [N m⁻³]."""
        return unit_weight * (self.head_at(x, z) - np.asarray(z, dtype=float))

    def node_flux(self, conductivity):
        """Per node, the net flux per unit width [m² s⁻¹] the finite volumes send from it to its
        neighbours: positive where the reservoir feeds the section, negative where water leaves it (the
        seepage face, a held outflow face), zero at free nodes to the solver's tolerance."""
        h = self.head
        out = sum(conductivity * w * (h - _shifted(h, di, dj)) for w, (di, dj) in zip(self._weights, _LINKS))
        return np.where(self.inside, out, 0.0)

    def _reservoir(self):
        return self.fixed & (np.arange(self.nx + 1)[:, None] == 0)

    def inflow(self, conductivity):
        """Discharge per unit width [m² s⁻¹] entering through the reservoir's face x = 0."""
        return float(self.node_flux(conductivity)[self._reservoir()].sum())

    def outflow(self, conductivity):
        """Discharge per unit width [m² s⁻¹] leaving elsewhere (the seepage face, a held face x = length)."""
        q = self.node_flux(conductivity)
        return -float(q[self.inside & ~self._reservoir() & (self.fixed | self.obstacle)].sum())


def pile(scene, head, spacing=0.001):
    """The steady seepage of a sandpile.SandPileScene's section under the reservoir level `head` [m]."""
    return SteadySeepage(scene.surface_height, scene.toe_x(), scene.pile_height, head, spacing)


def compare_run(out_dir, until=None, spacing=0.001):
    """The sand-pile example's run in out_dir against steady seepage of its section under each HDF5
    frame's head, up to time `until` [s] (default: the compliance onset's record): per frame the time,
    the head, the probes' pressures of the run (time_series.csv, the nearest record) and of steady seepage,
    and Bishop's factor (sandpile.limit_equilibrium) on the run's own weights with the run's pore pressures
    and with those of steady seepage. Point masses are taken from the frames' volumes and porosities."""
    import csv
    import types
    from . import results, sandpile
    with open(os.path.join(out_dir, "summary.json")) as f:
        summary = json.load(f)
    scene = sandpile.SandPileScene(**summary["scene"])
    cell = float(summary["cell_size_m"])
    spacing_points = cell / float(summary["points_per_cell"])
    with open(os.path.join(out_dir, "time_series.csv")) as f:
        series = list(csv.DictReader(f))
    if until is None:  # the onset's record and the frame written with it (frames fall between records by round-off)
        interval = float(series[1]["time_s"]) - float(series[0]["time_s"]) if len(series) > 1 else 0.0
        until = (summary.get("onset") or {}).get("time_s", math.inf) + 0.5 * interval
    gravity = np.asarray(summary["gravity_m_per_s2"], dtype=float)
    gamma_w = scene.water_density * float(np.linalg.norm(gravity))
    probe_names = [k for k in series[0] if k.startswith("p_")]
    probes = scene.probe_points()
    rows = []
    for record in results.read(os.path.join(out_dir, "sandpile.h5")):
        if record.time < float(series[0]["time_s"]) - 1e-9 or record.time > until + 1e-9:
            continue  # the starting state is not a seepage state; a frame is compared with the record written with it
        H = scene.head(record.time)
        steady = pile(scene, H, spacing)
        solid_key = next(k for k in record.sets if k.startswith("solid"))
        water_key = next(k for k in record.sets if k.startswith("water"))
        s, w = record.sets[solid_key], record.sets[water_key]
        solid = types.SimpleNamespace(pos=s["position"], mass=(1 - s["porosity"]) * scene.grain_density * s["volume"])
        water_mass = w["porosity"] * scene.water_density * w["volume"]
        wx, wz = w["position"][:, 0], w["position"][:, 2]
        in_soil = wz < scene.surface_height(wx)
        steady_p = np.where(in_soil, steady.pressure_at(wx, wz, gamma_w), 0.0)
        own = sandpile.limit_equilibrium(scene, solid, types.SimpleNamespace(pos=w["position"], mass=water_mass, porePressure=w["porePressure"]),
                                         gravity, cell, spacing_points)
        reference = sandpile.limit_equilibrium(scene, solid, types.SimpleNamespace(pos=w["position"], mass=water_mass, porePressure=steady_p),
                                               gravity, cell, spacing_points)
        nearest = min(series, key=lambda r: abs(float(r["time_s"]) - record.time))
        rows.append({"time_s": record.time, "head_m": H,
                     "run_probes_Pa": {name: float(nearest[name]) for name in probe_names},
                     "steady_probes_Pa": {name: float(steady.pressure_at(x, z, gamma_w)) for name, (x, _, z) in probes.items()},
                     "bishop_run": own.factor, "bishop_steady": reference.factor})
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description="The sand-pile example's run against steady seepage of its section (doc/sandpile.md)")
    parser.add_argument("out_dir", help="the example's output directory (summary.json, time_series.csv, sandpile.h5)")
    parser.add_argument("--until", type=float, default=None, help="last frame's time [s] (default: the compliance onset)")
    parser.add_argument("--spacing", type=float, default=0.001, help="the steady solution's grid spacing [m]")
    args = parser.parse_args(argv)
    for row in compare_run(args.out_dir, args.until, args.spacing):
        print("t = %6.2f s, head %.4f m: probes run %s Pa, steady %s Pa; Bishop F run %.3f, steady %.3f" % (
            row["time_s"], row["head_m"], ", ".join("%.1f" % v for v in row["run_probes_Pa"].values()),
            ", ".join("%.1f" % v for v in row["steady_probes_Pa"].values()), row["bishop_run"], row["bishop_steady"]))


if __name__ == "__main__":
    main()
