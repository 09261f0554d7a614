// Throughput benchmark (not a test). Prints one table row: the case, threads, soil point-steps per
// wall second and per CPU second (medians of the repeats), bytes per soil point, Δt, simulated
// seconds per wall second, CG iterations per step, and the share of each stage. A soil point is one
// solid point with its water point.
//
// Usage: mpm_bench CELLS_PER_SIDE|column STEPS REPEATS [dry] [explicit] [corrected] [linear] [uncached] [plain]
// CELLS_PER_SIDE: a saturated 3D block under gravity and a sudden 10 kPa on its top, two point sets
// (solid + water, 2×2×2 each per cell), cell averaging, at 0.5 × the scheme's critical step.
// `column`: the reference two-phase MPM's 3D consolidation column (cb-geo/mpm-benchmarks
// 3d/consolidation: 0.2 × 0.2 × 1 m, h = 2 cm, 5000 cells, 2×2×2 points per cell = 40 000 soil points,
// E = 9.8e7 Pa, ν = 0.3, n = 0.3, ρs = 2600, hydraulic conductivity 1e-3 m/s, Kw = 1e9 Pa, no gravity,
// 10 kPa on the drained top, Δt = 1e-5 s as there), rotated so that its height is along z.
// Options: `explicit`: the explicit scheme with semi-implicit drag and its pressure-mode damping (the
// block then takes Kw = 2.2e8 Pa, as the explicit sand pile); `corrected`: two defect corrections of
// the pressure per step (pressureCorrections = 2, theory.md eq. 8.7b); `dry`: solid points only (the
// soil-point column then counts solid points); `linear`: linear shape functions instead of uGIMP;
// `uncached`: every stage computes the stencil weights again (SolverSettings::reuseStencilWeights off);
// `plain`: the semi-implicit pressure without its dynamic subscales (darcySubscales off, theory.md eq. 8.6c).
#include "core/TwoPhaseSolver.hpp"
#include "support/Fixtures.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
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

double cpuSeconds()
{
	timespec t {};
	clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}
} // namespace

int main(int argc, char** argv)
{
	bool dry = false, explicitScheme = false, corrected = false, linear = false, uncached = false, plain = false, valid = argc >= 4;
	for (int a = 4; a < argc; ++a) {
		const std::string option = argv[a];
		if (option == "dry") dry = true;
		else if (option == "explicit") explicitScheme = true;
		else if (option == "corrected") corrected = true;
		else if (option == "linear") linear = true;
		else if (option == "uncached") uncached = true;
		else if (option == "plain") plain = true;
		else valid = false;
	}
	const bool column = valid && std::string(argv[1]) == "column";
	if (!valid || (!column && std::atoi(argv[1]) < 1)) {
		std::fprintf(stderr, "usage: %s CELLS_PER_SIDE|column STEPS REPEATS [dry] [explicit] [corrected] [linear] [uncached] [plain]\n", argv[0]);
		return 2;
	}
	const int    steps = std::atoi(argv[2]), repeats = std::atoi(argv[3]);
	const double h = column ? 0.02 : 0.01, g = 9.81;
	const Vec3   size = column ? Vec3(0.2, 0.2, 1.0) : Vec3::Constant(std::atoi(argv[1]) * h);
	const long   rssBefore = residentKiB();

	SoilParameters  soil;
	WaterParameters water;
	if (column) {
		soil.density               = 2600;
		soil.youngModulus          = 9.8e7;
		soil.poissonRatio          = 0.3;
		soil.porosity              = 0.3;
		soil.intrinsicPermeability = 1e-3 * water.viscosity / (water.density * g); // k = 1e-3 m/s
		water.bulkModulus          = 1e9;
	} else {
		// the semi-implicit rows take real water; the explicit ones the lowered Kw the explicit sand
		// pile runs with (its step follows the water's wave)
		water.bulkModulus          = explicitScheme ? 2.2e8 : 2.2e9;
		soil.intrinsicPermeability = 1e-11;
	}
	const auto    lattice = fixtures::lattice(Vec3::Zero(), size, h, 2);
	SolidPointSet solid   = fixtures::solidLattice(lattice, soil.porosity, soil.density);
	WaterPointSet fluid   = fixtures::waterLattice(lattice, soil.porosity, water.density);
	if (!column) fixtures::setGeostatic(solid, fluid, soil, water, g, size.z());
	// a sudden 10 kPa on the top face: the pressure responds and drains every step, so the solve works
	for (std::size_t p = 0; p < solid.size(); ++p)
		if (solid.position[p].z() > size.z() - lattice.spacing) solid.externalForce[p] = Vec3(0, 0, -10e3 * lattice.spacing * lattice.spacing);
	const std::size_t n = solid.size();
	const Domain d = fixtures::columnDomain(size, h);
	SolverSettings s;
	s.gravity = column ? Vec3::Zero() : Vec3(0, 0, -g);
	if (linear) s.shapeFunction = ShapeFunction::Linear;
	s.reuseStencilWeights = !uncached;
	s.darcySubscales      = !plain;
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
	const double dt = column ? 1e-5 : 0.5 * solver.timeStepLimits().critical;
	if (!(dt <= solver.timeStepLimits().critical)) {
		std::fprintf(stderr, "the time step %g s exceeds the critical step %g s\n", dt, solver.timeStepLimits().critical);
		return 1;
	}
	solver.step(dt); // warm-up: allocates the scratch arrays
	const long rssAfter = residentKiB();

	std::vector<double> rates, cpuRates, simulated;
	long                iterations = 0;
	auto                before = solver.stageSeconds();
	for (int r = 0; r < repeats; ++r) {
		const auto   start    = std::chrono::steady_clock::now();
		const double cpuStart = cpuSeconds();
		for (int i = 0; i < steps; ++i) {
			solver.step(dt);
			iterations += solver.lastPressureSolve().iterations;
		}
		const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
		rates.push_back(n * steps / seconds);
		cpuRates.push_back(n * steps / (cpuSeconds() - cpuStart));
		simulated.push_back(steps * dt / seconds);
	}
	std::sort(rates.begin(), rates.end());
	std::sort(cpuRates.begin(), cpuRates.end());
	std::sort(simulated.begin(), simulated.end());
	const double median  = rates[rates.size() / 2];
	const int    threads = omp_get_max_threads();
	std::string  label   = column ? "column " : "";
	if (dry) label += "dry ";
	if (explicitScheme) label += "explicit ";
	if (corrected) label += "2 corrections ";
	if (linear) label += "linear ";
	if (uncached) label += "uncached ";
	if (plain) label += "plain ";
	auto         after   = solver.stageSeconds();
	double       total   = 0;
	for (int i = 0; i < static_cast<int>(Stage::Count); ++i) total += after[i] - before[i];
	std::printf("%s%zu\t%d\t%.4g\t%.4g\t%.0f\t%.3g\t%.3g\t%.1f", label.c_str(), n, threads, median, cpuRates[cpuRates.size() / 2],
	            1024.0 * (rssAfter - rssBefore) / n, dt, simulated[simulated.size() / 2], static_cast<double>(iterations) / (steps * repeats));
	for (int i = 0; i < static_cast<int>(Stage::Count); ++i) std::printf("\t%s=%.1f", stageName(static_cast<Stage>(i)), 100 * (after[i] - before[i]) / total);
	std::printf("\n");
	if (std::getenv("MPM_BENCH_FINGERPRINT")) { // the final state, to compare builds (scripts/check-native.sh)
		double sum = 0;
		for (std::size_t p = 0; p < n; ++p) sum += solid.position[p].sum() + 1e-6 * solid.effectiveStress[p].sum();
		for (std::size_t p = 0; p < fluid.size(); ++p) sum += 1e-6 * fluid.porePressure[p] + fluid.velocity[p].sum();
		// and a hash of every bit of that state (FNV-1a): equal only where the results are equal bit for bit
		std::uint64_t bits = 1469598103934665603ull;
		auto          hash = [&bits](const double* v, std::size_t count) {
			for (std::size_t i = 0; i < count; ++i) {
				std::uint64_t word;
				std::memcpy(&word, v + i, sizeof word);
				for (int b = 0; b < 8; ++b) bits = (bits ^ ((word >> (8 * b)) & 0xff)) * 1099511628211ull;
			}
		};
		for (std::size_t p = 0; p < n; ++p) hash(solid.position[p].data(), 3), hash(solid.effectiveStress[p].data(), 6);
		for (std::size_t p = 0; p < fluid.size(); ++p) hash(&fluid.porePressure[p], 1), hash(fluid.velocity[p].data(), 3);
		std::fprintf(stderr, "fingerprint %.17g bits %016llx\n", sum, static_cast<unsigned long long>(bits));
	}
	return 0;
}
