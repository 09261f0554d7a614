// Shape-function properties at seeded random points, for every kernel (theory.md §3): partition
// of unity, linear completeness, gradients summing to zero and reproducing a linear field,
// gradients equal to central finite differences, and the documented support width.
#include "core/ShapeFunctions.hpp"

#include <gtest/gtest.h>

#include <random>

namespace {

using namespace mpm;

struct KernelCase {
	const char* name;
	Real        halfLength; // a = l_p/h
	bool        gimp;
};

void evaluate(const KernelCase& k, Real u, Weights1D& w, int& stencil)
{
	if (k.gimp) {
		GimpKernel::evaluate(u, k.halfLength, 1.0, w);
		stencil = GimpKernel::stencil;
	} else {
		LinearKernel::evaluate(u, 0, 1.0, w);
		stencil = LinearKernel::stencil;
	}
}

class ShapeFunctionProperties : public ::testing::TestWithParam<KernelCase> { };

TEST_P(ShapeFunctionProperties, HoldAtRandomPoints)
{
	const KernelCase k = GetParam();
	std::mt19937_64  rng(42);
	std::uniform_real_distribution<Real> position(3.0, 9.0); // interior: all stencil nodes exist
	const Real       support = 1 + (k.gimp ? k.halfLength : 0);
	for (int trial = 0; trial < 2000; ++trial) {
		const Real u = position(rng);
		Weights1D  w;
		int        stencil;
		evaluate(k, u, w, stencil);
		Real sum = 0, first = 0, gradSum = 0, gradFirst = 0;
		for (int i = 0; i < stencil; ++i) {
			const Real xi = w.first + i;
			sum += w.value[i];
			first += w.value[i] * xi;
			gradSum += w.gradient[i];
			gradFirst += w.gradient[i] * xi;
			EXPECT_GE(w.value[i], -1e-15);
			if (std::abs(u - xi) >= support) {
				EXPECT_EQ(w.value[i], 0) << "outside the support at u = " << u;
			}
		}
		EXPECT_NEAR(sum, 1, 1e-13) << "partition of unity at u = " << u;
		EXPECT_NEAR(first, u, 1e-12) << "linear completeness at u = " << u;
		EXPECT_NEAR(gradSum, 0, 1e-12) << "gradients of a constant at u = " << u;
		EXPECT_NEAR(gradFirst, 1, 1e-12) << "gradient of x at u = " << u;
		// nodes just outside the stencil are outside the support: the stencil is complete
		EXPECT_GE(std::abs(u - (w.first - 1)), support - 1e-12);
		EXPECT_GE(std::abs(u - (w.first + stencil)), support - 1e-12);
		// derivative against a central difference (away from the linear hat's kinks at nodes)
		const Real eps = 1e-6;
		if (!k.gimp && std::abs(u - std::round(u)) < 10 * eps) continue;
		Weights1D plus, minus;
		int       s2;
		evaluate(k, u + eps, plus, s2);
		evaluate(k, u - eps, minus, s2);
		for (int i = 0; i < stencil; ++i) {
			auto valueAt = [&](const Weights1D& ww, int node) {
				const int j = node - ww.first;
				return j >= 0 && j < stencil ? ww.value[j] : 0.0;
			};
			const Real fd = (valueAt(plus, w.first + i) - valueAt(minus, w.first + i)) / (2 * eps);
			EXPECT_NEAR(w.gradient[i], fd, 2e-6 * (1 + std::abs(fd)) / std::min<Real>(1, k.gimp ? k.halfLength * 4 : 1))
			        << k.name << " at u = " << u << ", node " << w.first + i;
		}
	}
}

INSTANTIATE_TEST_SUITE_P(Kernels, ShapeFunctionProperties,
                         ::testing::Values(KernelCase { "linear", 0, false }, KernelCase { "gimp_a0_1", 0.1, true }, KernelCase { "gimp_a0_25", 0.25, true },
                                           KernelCase { "gimp_a0_5", 0.5, true }, KernelCase { "gimp_a0", 0.0, true }),
                         [](const ::testing::TestParamInfo<KernelCase>& param) { return std::string(param.param.name); });

TEST(GimpKernel, ReducesToLinearHatAwayFromNodes)
{
	// for |ξ| in [a, 1 − a] GIMP equals the hat 1 − |ξ| (theory.md eq. 3.2, middle branch)
	Weights1D g, l;
	GimpKernel::evaluate(5.5, 0.25, 1.0, g);
	LinearKernel::evaluate(5.5, 0, 1.0, l);
	ASSERT_EQ(g.first, 5);
	ASSERT_EQ(l.first, 5);
	EXPECT_DOUBLE_EQ(g.value[0], l.value[0]); // node 5
	EXPECT_DOUBLE_EQ(g.value[1], l.value[1]); // node 6
	EXPECT_DOUBLE_EQ(g.value[2], 0);          // node 7 at distance 1.5 ≥ 1 + a
}

} // namespace
