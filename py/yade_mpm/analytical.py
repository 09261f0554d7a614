"""Closed-form solutions the examples and tests compare against (doc/theory.md §6).

The same formulas live in C++ for the core tests (tests/support/AnalyticalSolutions.hpp);
tests/yade/test_physics.py checks that both agree.
"""
import numpy as np


def terzaghi_pressure_ratio(zeta, time_factor, terms=200):
    """p/p0 of 1D consolidation at ζ = depth/H below the drained face, Tv = c_v t/H²
    (impermeable base at ζ = 1). Accepts numpy arrays for ζ."""
    zeta = np.asarray(zeta, dtype=float)
    m = np.arange(terms)
    M = np.pi * (2 * m + 1) / 2
    return np.sum((2 / M) * np.sin(np.multiply.outer(zeta, M)) * np.exp(-M * M * time_factor), axis=-1)


def terzaghi_degree(time_factor, terms=200):
    """Average degree of consolidation U(Tv) = 1 − Σ 2/M² exp(−M² Tv)."""
    m = np.arange(terms)
    M = np.pi * (2 * m + 1) / 2
    return 1 - np.sum(2 / (M * M) * np.exp(-M * M * np.asarray(time_factor, dtype=float)[..., None]), axis=-1)


def constrained_modulus(young_modulus, poisson_ratio):
    """E_oed = E(1−ν)/((1+ν)(1−2ν)) [Pa]."""
    return young_modulus * (1 - poisson_ratio) / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))


def consolidation_coefficient(intrinsic_permeability, viscosity, young_modulus, poisson_ratio, porosity, water_bulk_modulus):
    """c_v = (κ/μw)/(1/E_oed + n/Kw) [m² s⁻¹] (compressible water)."""
    e_oed = constrained_modulus(young_modulus, poisson_ratio)
    return (intrinsic_permeability / viscosity) / (1 / e_oed + porosity / water_bulk_modulus)


def undrained_pressure_ratio(young_modulus, poisson_ratio, porosity, water_bulk_modulus):
    """p0/q = (Kw/n)/(E_oed + Kw/n) for a sudden load q under uniaxial strain (1 for incompressible
    water, Kw = inf)."""
    if np.isinf(water_bulk_modulus):
        return 1.0
    stiffness = water_bulk_modulus / porosity
    return stiffness / (constrained_modulus(young_modulus, poisson_ratio) + stiffness)


def undrained_wave_speed(young_modulus, poisson_ratio, porosity, grain_density, water_density, water_bulk_modulus):
    """√((E_oed + Kw/n)/ρsat) [m s⁻¹]."""
    rho_sat = (1 - porosity) * grain_density + porosity * water_density
    return np.sqrt((constrained_modulus(young_modulus, poisson_ratio) + water_bulk_modulus / porosity) / rho_sat)


def mandel_roots(poisson_ratio, count=200, undrained_poisson_ratio=0.5):
    """The positive roots α_i of tan α = (1 − ν)/(ν_u − ν) α of Mandel's series (bisection on
    sin α − k α cos α, one root in (0, π/2) and one in (iπ, iπ + π/2) for each i ≥ 1)."""
    k = (1 - poisson_ratio) / (undrained_poisson_ratio - poisson_ratio)
    if not k > 1:
        raise ValueError("(1 − ν)/(ν_u − ν) = %r must exceed 1 (ν = %r, ν_u = %r)" % (k, poisson_ratio, undrained_poisson_ratio))
    f = lambda a: np.sin(a) - k * a * np.cos(a)
    roots = []
    for i in range(count):
        lo, hi = (1e-6, np.pi / 2) if i == 0 else (i * np.pi + 1e-12, i * np.pi + np.pi / 2)
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if f(lo) * f(mid) <= 0:
                hi = mid
            else:
                lo = mid
        roots.append(0.5 * (lo + hi))
    return np.array(roots)


def mandel_pressure_ratio(x_over_a, time_factor, poisson_ratio, terms=200):
    """p/p0 of Mandel's problem with incompressible constituents (B = 1, ν_u = 1/2; Abousleiman et al.
    1996): 2 Σ sin α_i/(α_i − sin α_i cos α_i) (cos(α_i x/a) − cos α_i) exp(−α_i² T), T = c t/a²,
    c = (κ/μw) E_oed; p0 = q/2 under a plate stress q (the total load 2F = 2a q)."""
    a = mandel_roots(poisson_ratio, terms)
    x = np.asarray(x_over_a, dtype=float)
    weights = np.sin(a) / (a - np.sin(a) * np.cos(a)) * np.exp(-a * a * time_factor)
    return 2 * np.sum(weights * (np.cos(np.multiply.outer(x, a)) - np.cos(a)), axis=-1)


_VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))  # xx yy zz yz xz xy


def undrained_response(young_modulus, poisson_ratio, porosity, water_bulk_modulus, stress=None, strain=None):
    """The undrained response of a saturated linear-elastic soil (incompressible grains, Biot
    coefficient 1, Biot modulus Kw/n) to a sudden, uniform load, with each of the six components
    either of the total stress increment or of the strain prescribed.

    stress, strain: dicts keyed by 'xx', 'yy', 'zz', 'yz', 'xz', 'xy' (tension-positive); every
    component must be given in exactly one of them (e.g. an oedometer under q: stress
    {'zz': -q}, strain {'xx': 0, 'yy': 0, 'yz': 0, 'xz': 0, 'xy': 0}). The water's volume balance
    without drainage gives Δp = −(Kw/n) tr Δε (compression-positive; Kw = inf: tr Δε = 0), the
    skeleton Δσ′ = C Δε (isotropic, E and ν), and Δσ = Δσ′ − Δp I.

    Returns (effective_stress 3×3 [Pa], pore_pressure [Pa], strain 3×3 [-]) of the increment.
    """
    stress, strain = dict(stress or {}), dict(strain or {})
    names = [a + b for a, b in ("xx", "yy", "zz", "yz", "xz", "xy")]
    for key in list(stress) + list(strain):
        if key not in names:
            raise ValueError("component %r is not one of %s" % (key, ", ".join(names)))
    both = set(stress) & set(strain)
    missing = [k for k in names if k not in stress and k not in strain]
    if both or missing:
        raise ValueError("each stress/strain component must be prescribed exactly once: %s given twice, %s missing"
                         % (sorted(both) or "none", missing or "none"))
    if not (young_modulus > 0 and -1 < poisson_ratio < 0.5 and 0 < porosity < 1 and water_bulk_modulus > 0):
        raise ValueError("need E > 0, −1 < ν < 0.5, 0 < n < 1 and Kw > 0 (inf allowed); got %r, %r, %r, %r"
                         % (young_modulus, poisson_ratio, porosity, water_bulk_modulus))
    lam = young_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))
    mu = young_modulus / (2 * (1 + poisson_ratio))
    # unknowns: the six strains (engineering shears) and Δp; rows: the six stress components
    # (prescribed or not) and the water's volume balance
    drained = np.zeros((6, 6))
    drained[:3, :3] = lam
    drained[:3, :3] += 2 * mu * np.eye(3)
    drained[3:, 3:] = mu * np.eye(3)
    system = np.zeros((7, 7))
    rhs = np.zeros(7)
    for i, name in enumerate(names):
        if name in stress:  # Δσ_i = Δσ′_i − Δp δ_i = (C Δε)_i − Δp δ_i
            system[i, :6] = drained[i]
            system[i, 6] = -1.0 if i < 3 else 0.0
            rhs[i] = float(stress[name])
        else:
            system[i, i] = 1.0
            rhs[i] = float(strain[name]) * (1 if i < 3 else 2)  # tensor shear → engineering shear
    if np.isinf(water_bulk_modulus):
        system[6, :3] = 1.0  # tr Δε = 0
    else:
        system[6, :3] = water_bulk_modulus / porosity
        system[6, 6] = 1.0  # Δp + (Kw/n) tr Δε = 0
    solution = np.linalg.solve(system, rhs)
    epsilon, pressure = solution[:6], solution[6]
    sigma_eff = drained @ epsilon
    effective = np.zeros((3, 3))
    strain_tensor = np.zeros((3, 3))
    for i, (a, b) in enumerate(_VOIGT):
        effective[a, b] = effective[b, a] = sigma_eff[i]
        strain_tensor[a, b] = strain_tensor[b, a] = epsilon[i] * (1 if i < 3 else 0.5)
    return effective, float(pressure), strain_tensor
