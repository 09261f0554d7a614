// Throughput benchmark (not a test): a saturated 3D block under gravity and a sudden 10 kPa on its
// top, two point sets (solid + water, 2×2×2 each per cell), uGIMP, cell averaging, the semi-implicit scheme (or, with
// `explicit`, the explicit one with semi-implicit drag and its pressure-mode damping). Prints one table row:
// soil points, threads, soil point-steps per second, per second per thread, bytes per soil point,
// and the share of each stage. A soil point is one solid point with its water point.
//
// Usage: mpm_bench CELLS_PER_SIDE STEPS REPEATS [dry|explicit|corrected]
// `corrected`: the semi-implicit scheme with two defect corrections of the pressure per step
// (pressureCorrections = 2, theory.md eq. 8.7b).
// With `dry` the block has solid points only (single-phase): the soil-point column then counts
// solid points.
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

using namespace mpm;

namespace {
long residentKiB()
{
	std::ifstream status("/proc/self/status");
	std::string   key;
	long          value = 0;
	while (status >> key) {
		if (key == "VmRSS:") {
			status >> value;
			return value;
		}
		std::getline(status, key);
	}
	return 0;
}
} // namespace

int main(int argc, char** argv)
{
	const std::string option = argc == 5 ? argv[4] : "";
	if (argc < 4 || argc > 5 || (argc == 5 && option != "dry" && option != "explicit" && option != "corrected")) {
		std::fprintf(stderr, "usage: %s CELLS_PER_SIDE STEPS REPEATS [dry|explicit|corrected]\n", argv[0]);
		return 2;
	}
	const bool dry = option == "dry", explicitScheme = option == "explicit", corrected = option == "corrected";
	const int    cells = std::atoi(argv[1]), steps = std::atoi(argv[2]), repeats = std::atoi(argv[3]);
	const double h = 0.01, side = cells * h, g = 9.81;
	const long   rssBefore = residentKiB();

	SoilParameters  soil;
	WaterParameters water;
	// the semi-implicit rows take real water; the explicit ones the lowered Kw the explicit sand pile
	// runs with (its step follows the water's wave)
	water.bulkModulus          = explicitScheme ? 2.2e8 : 2.2e9;
	soil.intrinsicPermeability = 1e-11;
	const auto    lattice = fixtures::lattice(Vec3::Zero(), Vec3::Constant(side), h, 2);
	SolidPointSet solid   = fixtures::solidLattice(lattice, soil.porosity, soil.density);
	WaterPointSet fluid   = fixtures::waterLattice(lattice, soil.porosity, water.density);
	fixtures::setGeostatic(solid, fluid, soil, water, g, side);
	// a sudden 10 kPa on the top face: the pressure responds and drains every step, so the solve works
	for (std::size_t p = 0; p < solid.size(); ++p)
		if (solid.position[p].z() > side - lattice.spacing) solid.externalForce[p] = Vec3(0, 0, -10e3 * lattice.spacing * lattice.spacing);
	const std::size_t n = solid.size();
	const Domain d = fixtures::columnDomain(Vec3::Constant(side), h);
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	if (corrected) s.pressureCorrections = 2;
	if (explicitScheme) {
		s.scheme              = TimeScheme::Explicit;
		s.pressureModeDamping = true; // as the explicit scheme runs in practice
	}
	TwoPhaseSolver solver(d, s);
	if (dry) {
		fluid = WaterPointSet {};
		for (auto& st : solid.effectiveStress) st *= (1 - soil.porosity) * soil.density / ((1 - soil.porosity) * soil.density + soil.porosity * water.density - water.density); // dry geostatic
	}
	solver.setPoints({ SolidSet { &solid, soil } }, dry ? std::vector<WaterPointSet*> {} : std::vector<WaterPointSet*> { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	solver.step(dt); // warm-up: allocates the scratch arrays
	const long rssAfter = residentKiB();

	std::vector<double> rates, simulated;
	long                iterations = 0;
	auto                before = solver.stageSeconds();
	for (int r = 0; r < repeats; ++r) {
		const auto start = std::chrono::steady_clock::now();
		for (int i = 0; i < steps; ++i) {
			solver.step(dt);
			iterations += solver.lastPressureSolve().iterations;
		}
		const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
		rates.push_back(n * steps / seconds);
		simulated.push_back(steps * dt / seconds);
	}
	std::sort(rates.begin(), rates.end());
	std::sort(simulated.begin(), simulated.end());
	const double median  = rates[rates.size() / 2];
	const int    threads = omp_get_max_threads();
	auto         after   = solver.stageSeconds();
	double       total   = 0;
	for (int i = 0; i < static_cast<int>(Stage::Count); ++i) total += after[i] - before[i];
	std::printf("%s%zu\t%d\t%.4g\t%.4g\t%.0f\t%.3g\t%.3g\t%.1f", dry ? "dry " : explicitScheme ? "explicit " : corrected ? "2 corrections " : "", n, threads, median, median / threads,
	            1024.0 * (rssAfter - rssBefore) / n, dt, simulated[simulated.size() / 2], static_cast<double>(iterations) / (steps * repeats));
	for (int i = 0; i < static_cast<int>(Stage::Count); ++i) std::printf("\t%s=%.1f", stageName(static_cast<Stage>(i)), 100 * (after[i] - before[i]) / total);
	std::printf("\n");
	if (std::getenv("MPM_BENCH_FINGERPRINT")) { // the final state, to compare builds (scripts/check-native.sh)
		double sum = 0;
		for (std::size_t p = 0; p < n; ++p) sum += solid.position[p].sum() + 1e-6 * solid.effectiveStress[p].sum();
		for (std::size_t p = 0; p < fluid.size(); ++p) sum += 1e-6 * fluid.porePressure[p] + fluid.velocity[p].sum();
		std::fprintf(stderr, "fingerprint %.17g\n", sum);
	}
	return 0;
}
