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
