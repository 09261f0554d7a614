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
