// Operators of the semi-implicit pressure projection (doc/theory.md §8.2): the mobility λ of eq. 8.5
// against the 2×2 nodal system it condenses, and its limits.
#include "core/PressureProjection.hpp"

#include <gtest/gtest.h>

namespace {

using namespace mpm;

// λ = [1−n, n] M⁻¹ [1−n, n]ᵀ per unit volume, M = [ρ̄s + QΔt, −QΔt; −QΔt, ρ̄w + QΔt], ρ̄s = (1−n)ρs,
// ρ̄w = nρw: what a unit pressure gradient does to the mixture's volume flux in one step.
double condensed(double n, double rhoS, double rhoW, double qdt)
{
	Eigen::Matrix2d M;
	M << (1 - n) * rhoS + qdt, -qdt, -qdt, n * rhoW + qdt;
	const Eigen::Vector2d share(1 - n, n);
	return share.dot(M.inverse() * share);
}

TEST(PressureMobility, EqualsTheCondensedNodalSystem)
{
	for (double n : { 0.2, 0.4, 0.7 })
		for (double qdt : { 0.0, 1e-3, 1.0, 1e3, 1e8 }) EXPECT_NEAR(stages::pressureMobility(n, 2650, 1000, qdt), condensed(n, 2650, 1000, qdt), 1e-12 * condensed(n, 2650, 1000, qdt));
}

TEST(PressureMobility, Limits)
{
	const double n = 0.4, rhoS = 2650, rhoW = 1000, rhoSat = (1 - n) * rhoS + n * rhoW;
	// no drag: each phase accelerates alone, λ0 = (1−n)/ρs + n/ρw
	EXPECT_NEAR(stages::pressureMobility(n, rhoS, rhoW, 0), (1 - n) / rhoS + n / rhoW, 1e-15);
	// infinite drag: the mixture moves as one body
	EXPECT_NEAR(stages::pressureMobility(n, rhoS, rhoW, 1e15), 1 / rhoSat, 1e-12 / rhoSat);
	// free water
	EXPECT_EQ(stages::pressureMobility(1, rhoS, rhoW, 0), 1 / rhoW);
}

} // namespace
