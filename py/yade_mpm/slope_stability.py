"""Limit-equilibrium slope stability (method of slices) on a 2D section, with the pore pressures of
an MPM run: the check geotechnical engineers know, next to the MPM's own failure (doc/theory.md §9).

* Bishop's simplified method (Bishop 1955): vertical equilibrium of each slice with horizontal
  interslice forces and moment equilibrium of the sliding mass about the circle's centre; for a
  surface that is not a circle (a circle clipped by a firm base) the same equations with the
  general moment arms (the λ = 0 case of Fredlund & Krahn's GLE, 1977).
* Spencer's method (Spencer 1967): force and moment equilibrium with parallel interslice forces of
  unknown inclination θ, for any slip surface (circular or not).
* `critical_circle`: a grid search over centres and radii for the smallest factor of safety.
* `Strength.davis()`: the strength a non-associated Mohr–Coulomb material mobilises at collapse
  (Davis 1968, as used by Sloan 2013 and Tschuchnigg et al. 2015): c* = β c, tan φ* = β tan φ,
  β = cos ψ cos φ / (1 − sin ψ sin φ). β = 1 for ψ = φ (associated flow).
* `infinite_slope_factor`: the closed form of a slope of constant inclination with a slip plane
  parallel to its surface.
* `section_from_points`: the section of an MPM run (weights from the points' masses, pore
  pressures from the water points), averaged across the out-of-plane direction.

Conventions: SI units; z up; pore pressure u compression-positive (the MPM's p), suction (u < 0)
counts as it does in the MPM's effective stress. The section's slope descends towards +x when
`direction` = +1 (the sand pile), towards −x when −1. Forces are per unit out-of-plane width.
"""
import math
from dataclasses import dataclass, replace
from typing import Callable, Optional

import numpy as np


@dataclass(frozen=True)
class Strength:
    """Mohr–Coulomb strength on the slip surface: τ = c + σ′ tan φ."""
    cohesion: float = 0.0          # c′ [Pa], ≥ 0
    friction_angle: float = 0.0    # φ′ [rad], [0, π/2)
    dilatancy_angle: Optional[float] = None  # ψ [rad], [0, φ′]; None: associated flow (ψ = φ′)

    def validate(self):
        if not self.cohesion >= 0:
            raise ValueError("Strength.cohesion = %r Pa is outside the valid range [0, inf)" % self.cohesion)
        if not 0 <= self.friction_angle < math.pi / 2:
            raise ValueError("Strength.friction_angle = %r rad is outside the valid range [0, π/2)" % self.friction_angle)
        if self.dilatancy_angle is not None and not 0 <= self.dilatancy_angle <= self.friction_angle:
            raise ValueError("Strength.dilatancy_angle = %r rad is outside the valid range [0, friction_angle = %r]"
                             % (self.dilatancy_angle, self.friction_angle))
        if self.cohesion == 0 and self.friction_angle == 0:
            raise ValueError("Strength has neither cohesion nor friction: every slope fails")
        return self

    def davis(self):
        """The associated strength with the same collapse load as this non-associated one
        (Davis 1968): c* = β c, tan φ* = β tan φ, β = cos ψ cos φ / (1 − sin ψ sin φ)."""
        self.validate()
        if self.dilatancy_angle is None:
            return self
        phi, psi = self.friction_angle, self.dilatancy_angle
        beta = math.cos(psi) * math.cos(phi) / (1 - math.sin(psi) * math.sin(phi))
        return Strength(cohesion=beta * self.cohesion, friction_angle=math.atan(beta * math.tan(phi)), dilatancy_angle=None)


@dataclass(frozen=True)
class Section:
    """A 2D slope section.

    surface_x, surface_z: the ground surface as a polyline, x increasing [m];
    column_weight(x, z_base): weight of the column above z_base at x per unit area, ∫ γ dz [Pa], point by
        point over numpy arrays;
    pore_pressure(x, z): u [Pa] (compression-positive), vectorised over numpy arrays;
    strength: the Strength used on the slip surface (apply .davis() before for non-associated flow);
    direction: +1 where the slope descends towards +x, −1 towards −x;
    base_z: a firm stratum the slip surface does not cross (None: no such stratum) [m].
    """
    surface_x: np.ndarray
    surface_z: np.ndarray
    column_weight: Callable
    pore_pressure: Callable
    strength: Strength
    direction: int = 1
    base_z: Optional[float] = None

    def validate(self):
        x = np.asarray(self.surface_x, dtype=float)
        if x.ndim != 1 or x.size < 2 or np.asarray(self.surface_z).shape != x.shape:
            raise ValueError("Section.surface_x and surface_z must be 1D arrays of the same length ≥ 2")
        if not np.all(np.diff(x) > 0):
            raise ValueError("Section.surface_x must increase strictly")
        if self.direction not in (1, -1):
            raise ValueError("Section.direction = %r is outside the valid values {+1, -1}" % self.direction)
        self.strength.validate()
        return self

    def surface(self, x):
        """Ground surface height z(x) [m]."""
        return np.interp(x, self.surface_x, self.surface_z)


def _clamp(values, low, high):
    """np.clip(values, low, high) by two ufuncs: the same numbers, without np.clip's argument checks,
    which cost several times the arithmetic on the short arrays of a circle search's inner loop."""
    return np.minimum(np.maximum(values, low), high)


def uniform_section(surface_x, surface_z, unit_weight, strength, pore_pressure=None, direction=1, base_z=None):
    """A section of one material of unit weight γ [N m⁻³] (> 0); pore_pressure(x, z) [Pa] or None (dry)."""
    if not unit_weight > 0:
        raise ValueError("unit_weight = %r N/m³ is outside the valid range (0, inf)" % unit_weight)
    surface_x = np.asarray(surface_x, dtype=float)
    surface_z = np.asarray(surface_z, dtype=float)

    def column_weight(x, z_base):
        return unit_weight * np.maximum(np.interp(x, surface_x, surface_z) - z_base, 0)

    dry = lambda x, z: np.zeros(np.broadcast(x, z).shape)
    return Section(surface_x, surface_z, column_weight, pore_pressure or dry, strength, direction, base_z).validate()


@dataclass
class Slices:
    """The slices of one slip surface, in the frame where the mass slides towards +x (x mirrored
    for a section with direction −1). Arrays of one value per slice."""
    x: np.ndarray       # base midpoint x [m]
    z: np.ndarray       # base midpoint z [m]
    width: np.ndarray   # b [m]
    alpha: np.ndarray   # base inclination, > 0 where the base descends towards +x [rad]
    weight: np.ndarray  # W per unit width [N m⁻¹]
    pore_pressure: np.ndarray  # u at the base midpoint [Pa]
    cohesion: float
    tan_friction: float
    centre: Optional[tuple] = None  # moment centre (x, z) of a circle, in the same frame
    direction: int = 1  # the section's: x of this frame × direction is the section's x

    @property
    def base_length(self):
        return self.width / np.cos(self.alpha)


def slices_of_surface(section, slip_x, slip_z, count=40):
    """Slices of a slip surface given as a polyline (slip_x increasing, in the section's frame)
    from its entry to its exit on the ground surface; count slices of equal width."""
    section.validate()
    slip_x = np.asarray(slip_x, dtype=float)
    slip_z = np.asarray(slip_z, dtype=float)
    edges = np.linspace(slip_x[0], slip_x[-1], count + 1)
    return _build_slices(section, edges, lambda x: np.interp(x, slip_x, slip_z), None)


def slices_of_circle(section, centre, radius, count=40, min_depth=0.0, free_ground=None):
    """Slices of the circle (centre (x, z) [m], radius [m]) where it runs below the ground surface
    (clipped by section.base_z), or None where it does not cut a sliding mass deeper than
    min_depth [m], leaves the section's ends, or breaks through the ground outside free_ground
    ((x_lo, x_hi) [m], section frame; None: anywhere)."""
    return _slices_of_circles(section, centre, np.array([radius], dtype=float), count, min_depth, free_ground)[0]


def _circle_base(section, centre, radius):
    """The slip surface z(x) of a circle: its lower arc, clipped by section.base_z."""
    xc, zc = centre

    def base(xq):
        zb = zc - np.sqrt(np.maximum(radius * radius - (xq - xc) ** 2, 0))
        return zb if section.base_z is None else np.maximum(zb, section.base_z)
    return base


def _slices_of_circles(section, centre, radii, count, min_depth, free_ground):
    """slices_of_circle for each of the radii about one centre, as a list: the 801 samples of every
    circle in one array (a search evaluates thousands of circles, most rejected, and the cost of one
    alone is numpy's overhead per call); the same operations per sample, so the same numbers."""
    section.validate()
    xc, zc = centre
    found = [None] * radii.size
    x_lo = np.maximum(xc - radii, section.surface_x[0])
    x_hi = np.minimum(xc + radii, section.surface_x[-1])
    spanning = np.flatnonzero(x_hi > x_lo)
    if spanning.size == 0:
        return found
    x = np.linspace(x_lo[spanning], x_hi[spanning], 801, axis=1)
    depth = section.surface(x) - _circle_base(section, centre, radii[spanning, None])(x)
    deepest_of = np.argmax(depth, axis=1)
    for row, k in enumerate(spanning):
        deepest = int(deepest_of[row])
        # nothing below the ground, or the sliding mass thinner than min_depth
        if not depth[row, deepest] > 0 or depth[row, deepest] < min_depth:
            continue
        # the contiguous run that holds the deepest point is the sliding mass: from after the last
        # sample outside before it to before the first outside after it
        inside = depth[row] > 0
        outside_before = np.flatnonzero(~inside[:deepest])
        lo = int(outside_before[-1]) + 1 if outside_before.size else 0
        outside_after = np.flatnonzero(~inside[deepest + 1:])
        hi = deepest + int(outside_after[0]) if outside_after.size else x.shape[1] - 1
        if lo == 0 or hi == x.shape[1] - 1:
            # the lower arc ends under the ground (the circle's side, or the section's end): not a
            # slip surface from ground to ground
            continue
        # entry and exit where the depth crosses zero (linear between samples)
        xs, ds = x[row], depth[row]
        x_in = xs[lo - 1] + (xs[lo] - xs[lo - 1]) * (-ds[lo - 1]) / (ds[lo] - ds[lo - 1])
        x_out = xs[hi] + (xs[hi + 1] - xs[hi]) * ds[hi] / (ds[hi] - ds[hi + 1])
        if free_ground is not None and not (free_ground[0] <= x_in and x_out <= free_ground[1]):
            continue
        edges = np.linspace(x_in, x_out, count + 1)
        found[k] = _build_slices(section, edges, _circle_base(section, centre, radii[k]), (xc, zc))
    return found


def _build_slices(section, edges, base, centre):
    """Slices between edges (section frame) under the slip surface z = base(x); returned in the
    frame sliding towards +x."""
    mid = 0.5 * (edges[:-1] + edges[1:])
    width = np.diff(edges)
    z_mid = base(mid)
    z_edges = base(edges)  # base and column_weight act point by point: once on all edges, then each side
    # weight by Simpson's rule over each slice (exact for a linear surface and a straight base)
    w_edges = section.column_weight(edges, z_edges)
    w_lo, w_hi = w_edges[:-1], w_edges[1:]
    w_mid = section.column_weight(mid, z_mid)
    weight = width * (w_lo + 4 * w_mid + w_hi) / 6
    slope = (z_edges[1:] - z_edges[:-1]) / width
    u = np.asarray(section.pore_pressure(mid, z_mid), dtype=float)
    s = section.direction
    strength = section.strength
    if s == 1:
        x_frame, alpha = mid, -np.arctan(slope)
        c = centre
    else:  # mirror x so that the mass slides towards +x
        order = slice(None, None, -1)
        x_frame, alpha = -mid[order], np.arctan(slope)[order]
        z_mid, width, weight, u = z_mid[order], width[order], weight[order], u[order]
        c = None if centre is None else (-centre[0], centre[1])
    return Slices(x_frame, z_mid, width, alpha, weight, u, strength.cohesion, math.tan(strength.friction_angle), c, s)


def bishop_simplified(slices, tolerance=1e-8, max_iterations=200):
    """Bishop's simplified factor of safety (moments about slices.centre; horizontal interslice
    forces). For a circle: F = Σ (c l + N′ tan φ) R / Σ W (x_c − x), N′ = [W − u b − c l sin α / F]/m_α,
    m_α = cos α + sin α tan φ / F. Returns F (inf where nothing drives the mass, nan where no
    positive F balances it, where m_α < 0.2 on a slice, or where the iteration does not converge)."""
    if slices.centre is None:
        raise ValueError("bishop_simplified needs a moment centre (a circular surface); use spencer for other surfaces")
    xc, zc = slices.centre
    a, b, W, u = slices.alpha, slices.width, slices.weight, slices.pore_pressure
    c, t = slices.cohesion, slices.tan_friction
    l = slices.base_length
    rx, rz = slices.x - xc, slices.z - zc
    cos_a, sin_a = np.cos(a), np.sin(a)
    shear_arm = -(rx * sin_a + rz * cos_a)   # R on a circle
    normal_arm = rx * cos_a - rz * sin_a     # 0 on a circle
    driving = -np.sum(W * rx)
    if driving <= 0:
        return math.inf
    # the iteration's terms that do not depend on F, formed once (the same numbers: each as the left-to-right
    # products and differences of the formulas); ndarray methods, not np.* wrappers: the arrays are short
    sin_tan, effective_weight, cohesion_force = sin_a * t, W - u * b, c * l
    cohesion_lift, water_force = cohesion_force * sin_a, u * l
    F = 1.0
    for _ in range(max_iterations):
        m_alpha = cos_a + sin_tan / F
        if (m_alpha < 0.2).any():
            # m_α < 0.2 at a steep exit: the normal force there is unreliable and the method is known
            # to fail (Whitman & Bailey 1967, who recommend discarding such surfaces): no admissible F
            return math.nan
        N_eff = (effective_weight - cohesion_lift / F) / m_alpha
        resisting = ((cohesion_force + N_eff * t) * shear_arm).sum()
        F_new = resisting / (driving + ((N_eff + water_force) * normal_arm).sum())
        if not (np.isfinite(F_new) and F_new > 0):
            return math.nan  # the base's normal forces outweigh the driving moment: no admissible F
        if abs(F_new - F) <= tolerance * abs(F):
            return float(F_new)
        F = F_new
    return math.nan  # no convergence: no F is reported for this surface


def _spencer_q(slices, F, theta):
    """Net interslice force on each slice; nan where a slice's denominator F cos(α + θ) +
    tan φ sin(α + θ) is not positive (the normal force on its base would change sign: the same
    inadmissible range as Bishop's m_α ≤ 0)."""
    a, W, u, l = slices.alpha, slices.weight, slices.pore_pressure, slices.base_length
    c, t = slices.cohesion, slices.tan_friction
    denominator = F * np.cos(a + theta) + t * np.sin(a + theta)
    if np.any(denominator <= 0):
        return np.full(a.shape, np.nan)
    return (c * l + (W * np.cos(a) - u * l) * t - F * W * np.sin(a)) / denominator


def _root(f, lo=0.05, hi=50.0, samples=120, tolerance=1e-10):
    """The smallest root of f in [lo, hi] (log-spaced scan, then bisection), or nan."""
    grid = np.geomspace(lo, hi, samples)
    values = np.array([f(x) for x in grid])
    for i in range(samples - 1):
        if np.isfinite(values[i]) and np.isfinite(values[i + 1]) and values[i] * values[i + 1] <= 0:
            a, b, fa = grid[i], grid[i + 1], values[i]
            for _ in range(200):
                m = 0.5 * (a + b)
                fm = f(m)
                if fa * fm <= 0:
                    b = m
                else:
                    a, fa = m, fm
                if b - a <= tolerance * m:
                    break
            return 0.5 * (a + b)
    return math.nan


def spencer(slices):
    """Spencer's factor of safety and interslice force inclination θ [rad] for any slip surface.
    Per slice the net interslice force Q (inclination θ, through the base midpoint) from the
    slice's equilibrium normal and parallel to its base: Q = [c l + (W cos α − u l) tan φ −
    F W sin α] / [F cos(α + θ) + tan φ sin(α + θ)]; F and θ make Σ Q = 0 (forces) and
    Σ Q (x sin θ − z cos θ) = 0 (moments). Solved as F_f(θ) from the force equation, then the θ
    whose moments vanish at F_f(θ): on a long translational surface the moment sum hardly
    depends on F, so the usual F_m(θ) may not exist while the pair does."""
    x, z = slices.x - slices.x.mean(), slices.z - slices.z.mean()

    def force_factor(theta):
        return _root(lambda F: np.sum(_spencer_q(slices, F, theta)))

    def moment_at_force_balance(theta):
        F = force_factor(theta)
        if not np.isfinite(F):
            return math.nan, F
        return float(np.sum(_spencer_q(slices, F, theta) * (x * math.sin(theta) - z * math.cos(theta)))), F

    thetas = np.radians(np.linspace(-60, 60, 49))
    moments = np.array([moment_at_force_balance(th)[0] for th in thetas])
    for i in range(thetas.size - 1):
        if np.isfinite(moments[i]) and np.isfinite(moments[i + 1]) and moments[i] * moments[i + 1] <= 0:
            a, b, ma = thetas[i], thetas[i + 1], moments[i]
            for _ in range(60):
                m = 0.5 * (a + b)
                mm = moment_at_force_balance(m)[0]
                if not np.isfinite(mm):
                    break
                if ma * mm <= 0:
                    b = m
                else:
                    a, ma = m, mm
                if b - a < 1e-10:
                    break
            theta = 0.5 * (a + b)
            return float(force_factor(theta)), float(theta)
    raise RuntimeError("spencer: no inclination θ in [−60°, 60°] balances forces and moments on this surface")


@dataclass
class CriticalCircle:
    factor: float      # the smallest factor of safety found
    centre: tuple      # (x, z) [m], section frame
    radius: float      # [m]
    slices: Slices     # its slices (frame sliding towards +x)
    searched: int      # circles evaluated

    def surface(self):
        """The slip surface's base midpoints as (x, z) arrays in the section's frame, x increasing."""
        x = self.slices.x * self.slices.direction
        order = np.argsort(x)
        return x[order], self.slices.z[order]

    def describe(self):
        """Where the circle lies, for a summary: its centre (x, z) and radius [m], the span of its
        slices' base midpoints along x [m] and their lowest elevation [m] (the section's frame)."""
        x, z = self.surface()
        return {"factor": float(self.factor), "centre_m": [float(c) for c in self.centre], "radius_m": float(self.radius),
                "from_x_m": float(x.min()), "to_x_m": float(x.max()), "lowest_z_m": float(z.min())}


def _corners(section, min_turn=math.radians(5)):
    """Vertices of the ground polyline where its inclination turns by more than min_turn: a steep
    slope's critical circle leaves through its toe, a corner."""
    x, z = np.asarray(section.surface_x, dtype=float), np.asarray(section.surface_z, dtype=float)
    angle = np.arctan2(np.diff(z), np.diff(x))
    turn = np.abs(np.diff(angle)) > min_turn
    return x[1:-1][turn], z[1:-1][turn]


def critical_circle(section, centres_x, centres_z, radii_per_centre=12, min_depth=0.0, slice_count=30,
                    method=bishop_simplified, zooms=3, free_ground=None):
    """Search for the circle of smallest factor of safety: every centre (x, z) of the grid
    centres_x × centres_z [m] with radii_per_centre radii from the circle that first cuts the ground
    to the one tangent to section.base_z (or reaching as deep below the ground's lowest point as
    the ground is high, without a base), plus the circles through the ground's corners (a steep
    slope's critical circle passes through its toe); circles shallower than min_depth [m] are
    skipped (a cohesionless slope's critical surface is otherwise its skin). Then `zooms` times a
    grid of 7 × 7 centres one spacing around the best, the spacing and radius step shrunk 3×.
    free_ground (x_lo, x_hi) [m]: the stretch of ground surface (section frame) a slide may break
    through at both ends, e.g. outside a lid whose reaction the method does not know; None: anywhere.
    method: bishop_simplified or spencer (its F is taken)."""
    section.validate()
    if not radii_per_centre >= 1:
        raise ValueError("radii_per_centre = %r is outside the valid range [1, inf)" % radii_per_centre)
    if not min_depth >= 0:
        raise ValueError("min_depth = %r m is outside the valid range [0, inf)" % min_depth)
    ground_x = np.linspace(section.surface_x[0], section.surface_x[-1], 400)
    ground_z = section.surface(ground_x)
    bottom = section.base_z if section.base_z is not None else ground_z.min() - (ground_z.max() - ground_z.min())
    corner_x, corner_z = _corners(section)
    best, searched = None, 0

    def scan(xs, zs, radius_window):
        nonlocal best, searched
        for xc in xs:
            for zc in zs:
                r_min = float(np.min(np.hypot(ground_x - xc, ground_z - zc)))
                r_max = zc - bottom
                if radius_window is not None:
                    r_min, r_max = max(r_min, radius_window[0]), min(r_max, radius_window[1])
                if r_max <= r_min:
                    continue
                radii = np.concatenate([np.linspace(r_min, r_max, radii_per_centre + 1)[1:],
                                        np.hypot(corner_x - xc, corner_z - zc) * (1 + 1e-9)])
                radii = radii[(radii > r_min) & (radii <= r_max)]
                for radius, slices in zip(radii, _slices_of_circles(section, (xc, zc), radii, slice_count, min_depth, free_ground)):
                    if slices is None:
                        continue
                    searched += 1
                    F = method(slices)
                    F = F[0] if isinstance(F, tuple) else F
                    if np.isfinite(F) and F > 0 and (best is None or F < best.factor):
                        best = CriticalCircle(float(F), (float(xc), float(zc)), float(radius), slices, 0)

    xs, zs = np.atleast_1d(np.asarray(centres_x, dtype=float)), np.atleast_1d(np.asarray(centres_z, dtype=float))
    scan(xs, zs, None)
    if best is None:
        raise ValueError("critical_circle: no circle of the search grid cuts a sliding mass deeper than min_depth = %r m%s"
                         % (min_depth, "" if free_ground is None else " breaking through the ground within free_ground = %r m" % (tuple(free_ground),)))
    dx = np.ptp(xs) / max(xs.size - 1, 1) if xs.size > 1 else 0.1 * (ground_z.max() - bottom)
    dz = np.ptp(zs) / max(zs.size - 1, 1) if zs.size > 1 else 0.1 * (ground_z.max() - bottom)
    dr = (ground_z.max() - bottom) / radii_per_centre
    for _ in range(zooms):
        (xc, zc), r = best.centre, best.radius
        scan(xc + dx * np.linspace(-1, 1, 7), zc + dz * np.linspace(-1, 1, 7), (r - 2 * dr, r + 2 * dr))
        dx, dz, dr = dx / 3, dz / 3, dr / 3
    best.searched = searched
    return best


def _rise_to_ground(section, x0, z0, angle, towards):
    """Where the line from (x0, z0) rising at `angle` [rad] above the horizontal, towards −x (towards = −1)
    or +x (+1), meets the ground: (x, z) [m]; (x0, z0) itself where it lies on or above the ground."""
    gap = lambda t: section.surface(x0 + towards * t * math.cos(angle)) - (z0 + t * math.sin(angle))
    if not gap(0.0) > 0:
        return float(x0), float(z0)
    span = float(np.ptp(section.surface_x)) + float(np.ptp(section.surface_z))
    lo, hi = 0.0, span  # the ground lies within the section's extent: past it the line is above
    if gap(hi) > 0:
        raise ValueError("the line from (%g, %g) m at %g° does not reach the ground within the section" % (x0, z0, math.degrees(angle)))
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gap(mid) > 0 else (lo, mid)
    t = 0.5 * (lo + hi)
    return float(x0 + towards * t * math.cos(angle)), float(z0 + t * math.sin(angle))


def band_slip_surface(section, band_x, band_z):
    """The slip surface of a back-analysis through a shear band: the band's base (band_x increasing from
    the scarp's end to the exit's, z; section frame, the mass sliding towards +x) [m], closed to the ground
    at both ends on Rankine's planes for the section's friction angle φ — up behind the scarp at 45° + φ/2
    (the active wedge behind a slide) and up beyond the exit at 45° − φ/2 (the passive wedge in front of it),
    the planes of Rankine's (1857) active and passive states, for a slip surface observed only where it runs
    through the ground. Returns the polyline (x, z) for slices_of_surface."""
    section.validate()
    x, z = np.asarray(band_x, dtype=float), np.asarray(band_z, dtype=float)
    if x.ndim != 1 or x.size < 2 or x.shape != z.shape or not np.all(np.diff(x) > 0):
        raise ValueError("band_x = %r m must be at least two increasing abscissae, one per band_z" % (x.tolist(),))
    phi = section.strength.friction_angle
    entry = _rise_to_ground(section, x[0], z[0], 0.25 * math.pi + 0.5 * phi, -1)
    leave = _rise_to_ground(section, x[-1], z[-1], 0.25 * math.pi - 0.5 * phi, +1)
    xs, zs = [entry[0]] + x.tolist() + [leave[0]], [entry[1]] + z.tolist() + [leave[1]]
    keep = np.concatenate([[True], np.diff(xs) > 0])  # an end already on the ground adds no segment
    return np.asarray(xs)[keep], np.asarray(zs)[keep]


def back_analysis_factor(section, band_x, band_z, slice_count=40):
    """Spencer's factor of safety on the slip surface through a shear band's base (band_slip_surface): the
    engineer's back-analysis of an observed slide, whose factor at failure should be 1 where the section's
    weights, pore pressures and strength are the ones the slide failed under. Raises spencer's RuntimeError
    where no interslice inclination balances the mass's moments (seen on small, shallow slides at low loads)."""
    slip_x, slip_z = band_slip_surface(section, band_x, band_z)
    return spencer(slices_of_surface(section, slip_x, slip_z, count=slice_count))[0]


def infinite_slope_factor(slope_angle, depth, unit_weight, strength, pore_pressure=0.0):
    """F of an infinite slope (inclination β [rad]) on a slip plane parallel to its surface at
    vertical depth d [m]: F = [c + (γ d cos²β − u) tan φ] / (γ d sin β cos β), u the pore pressure
    on the plane [Pa] (seepage parallel to the slope with the water table at the surface:
    u = γw d cos²β)."""
    strength.validate()
    normal = unit_weight * depth * math.cos(slope_angle) ** 2 - pore_pressure
    return (strength.cohesion + normal * math.tan(strength.friction_angle)) / (unit_weight * depth * math.sin(slope_angle) * math.cos(slope_angle))


def section_from_points(solid_positions, solid_masses, water_positions, water_masses, water_pressures, gravity,
                        width, bin_size, strength, direction=1, base_z=None, surface_offset=0.0):
    """The 2D section (x–z) of an MPM run, averaged over the out-of-plane width [m].

    Weights: the masses of both phases' points × |gravity| [m s⁻²], binned on a bin_size [m]
    raster (one cell is a good choice: every bin holds points); a slice's column weight is the
    binned weight above its base, the bin it cuts counted in proportion. Pore pressure: the mean
    of the water points' pressures in each bin, bilinear between bin centres, 0 where a bin holds
    no water (dry). Ground surface: the highest solid point of each bin column + surface_offset
    [m] (half a point spacing puts it on the points' domain edge)."""
    if not bin_size > 0:
        raise ValueError("bin_size = %r m is outside the valid range (0, inf)" % bin_size)
    if not width > 0:
        raise ValueError("width = %r m is outside the valid range (0, inf)" % width)
    g = float(np.linalg.norm(gravity))
    sp, wp = np.asarray(solid_positions, dtype=float), np.asarray(water_positions, dtype=float)
    all_pos = np.vstack([sp, wp]) if wp.size else sp
    x0 = all_pos[:, 0].min() - 0.5 * bin_size
    z0 = min(all_pos[:, 2].min(), base_z if base_z is not None else np.inf) - 0.5 * bin_size
    nx = int(np.ceil((all_pos[:, 0].max() + 0.5 * bin_size - x0) / bin_size)) + 1
    nz = int(np.ceil((all_pos[:, 2].max() + 0.5 * bin_size - z0) / bin_size)) + 1

    def bin_index(pos):
        i = np.clip(((pos[:, 0] - x0) / bin_size).astype(int), 0, nx - 1)
        k = np.clip(((pos[:, 2] - z0) / bin_size).astype(int), 0, nz - 1)
        return i, k

    # weight per unit area of the x–z plane in each bin [N m⁻²] per unit of z: γ_bin [N m⁻³]
    gamma = np.zeros((nx, nz))
    i, k = bin_index(sp)
    np.add.at(gamma, (i, k), np.asarray(solid_masses) * g)
    if wp.size:
        i, k = bin_index(wp)
        np.add.at(gamma, (i, k), np.asarray(water_masses) * g)
    gamma /= bin_size * bin_size * width
    # weight above the bottom of each bin, per unit area [Pa]
    above = np.cumsum(gamma[:, ::-1], axis=1)[:, ::-1] * bin_size
    centres_x = x0 + bin_size * (np.arange(nx) + 0.5)
    z_edges = z0 + bin_size * np.arange(nz + 1)

    def column_weight_of(cols, z_base):
        # weight above z_base [Pa] in the bin columns cols: the bins above in full, the cut one in part
        kk = _clamp(np.floor((z_base - z0) / bin_size).astype(int), 0, nz - 1)
        frac = _clamp((z_edges[kk + 1] - z_base) / bin_size, 0, 1)
        upper = np.where(kk + 1 < nz, above[cols, np.minimum(kk + 1, nz - 1)], 0.0)
        return upper + frac * gamma[cols, kk] * bin_size

    def column_weight(x, z_base):
        x, z_base = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(z_base, dtype=float))
        fx = _clamp((x - centres_x[0]) / bin_size, 0, nx - 1 - 1e-9)
        i0 = fx.astype(int)
        tx = fx - i0
        return (1 - tx) * column_weight_of(i0, z_base) + tx * column_weight_of(np.minimum(i0 + 1, nx - 1), z_base)

    # pore pressure: bin means of the water points, bilinear between bin centres
    p_sum = np.zeros((nx, nz))
    p_count = np.zeros((nx, nz))
    if wp.size:
        i, k = bin_index(wp)
        np.add.at(p_sum, (i, k), np.asarray(water_pressures, dtype=float))
        np.add.at(p_count, (i, k), 1.0)
    p_bin = np.divide(p_sum, p_count, out=np.zeros_like(p_sum), where=p_count > 0)
    centres_z = z0 + bin_size * (np.arange(nz) + 0.5)

    def pore_pressure(x, z):
        x, z = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(z, dtype=float))
        fx = _clamp((x - centres_x[0]) / bin_size, 0, nx - 1 - 1e-9)
        fz = _clamp((z - centres_z[0]) / bin_size, 0, nz - 1 - 1e-9)
        i0, k0 = fx.astype(int), fz.astype(int)
        i1, k1 = np.minimum(i0 + 1, nx - 1), np.minimum(k0 + 1, nz - 1)
        tx, tz = fx - i0, fz - k0
        return ((1 - tx) * (1 - tz) * p_bin[i0, k0] + tx * (1 - tz) * p_bin[i1, k0]
                + (1 - tx) * tz * p_bin[i0, k1] + tx * tz * p_bin[i1, k1])

    # ground surface: top of the solid points per bin column
    top = np.full(nx, -np.inf)
    i, _ = bin_index(sp)
    np.maximum.at(top, i, sp[:, 2] + surface_offset)
    has = np.isfinite(top)
    floor = base_z if base_z is not None else z0
    top = np.where(has, top, floor)
    return Section(centres_x, top, column_weight, pore_pressure, strength, direction, base_z).validate()
