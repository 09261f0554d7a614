// Throughput benchmark (not a test): a saturated 3D block under gravity, two point sets (solid +
// water, 2×2×2 each per cell), uGIMP, semi-implicit drag, cell averaging. Prints one table row:
// soil points, threads, soil point-steps per second, per second per thread, bytes per soil point,
// and the share of each stage. A soil point is one solid point with its water point.
//
// Usage: mpm_bench CELLS_PER_SIDE STEPS REPEATS
#include "core/TwoPhaseSolver.hpp"

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
	if (argc != 4) {
		std::fprintf(stderr, "usage: %s CELLS_PER_SIDE STEPS REPEATS\n", argv[0]);
		return 2;
	}
	const int    cells = std::atoi(argv[1]), steps = std::atoi(argv[2]), repeats = std::atoi(argv[3]);
	const double h = 0.01, side = cells * h, g = 9.81;
	const long   rssBefore = residentKiB();

	SoilParameters  soil;
	WaterParameters water;
	water.bulkModulus          = 2.2e8;
	soil.intrinsicPermeability = 1e-11;
	const int     ppc = 2, perSide = cells * ppc;
	const std::size_t n = static_cast<std::size_t>(perSide) * perSide * perSide;
	const double  spacing = h / ppc, V = spacing * spacing * spacing;
	SolidPointSet solid;
	WaterPointSet fluid;
	solid.resize(n);
	fluid.resize(n);
	const double rhoSat = (1 - soil.porosity) * soil.density + soil.porosity * water.density;
	std::size_t  p      = 0;
	for (int k = 0; k < perSide; ++k)
		for (int j = 0; j < perSide; ++j)
			for (int i = 0; i < perSide; ++i, ++p) {
				const Vec3 x = spacing * Vec3(i + 0.5, j + 0.5, k + 0.5);
				for (MaterialPointSet* set : { static_cast<MaterialPointSet*>(&solid), static_cast<MaterialPointSet*>(&fluid) }) {
					set->position[p]   = x;
					set->volume[p]     = V;
					set->halfLength[p] = Vec3::Constant(spacing / 2);
				}
				solid.mass[p]              = (1 - soil.porosity) * soil.density * V;
				solid.initialVolume[p]     = V;
				solid.initialHalfLength[p] = solid.halfLength[p];
				solid.porosity[p]          = soil.porosity;
				fluid.mass[p]              = soil.porosity * water.density * V;
				fluid.porosity[p]          = soil.porosity;
				const double depth         = side - x.z();
				fluid.porePressure[p]      = water.density * g * depth;
				const double sz            = -(rhoSat - water.density) * g * depth;
				solid.effectiveStress[p] << 0.5 * sz, 0.5 * sz, sz, 0, 0, 0;
			}
	Domain d;
	d.upper    = Vec3::Constant(side);
	d.cellSize = h;
	for (int f = 0; f < 4; ++f) d.boundaries.walls[f] = { SolidWall::Slip, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Impermeable };
	d.boundaries.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Free, WaterWall::Drained };
	SolverSettings s;
	s.gravity = Vec3(0, 0, -g);
	TwoPhaseSolver solver(d, s);
	solver.setPoints({ SolidSet { &solid, soil } }, { &fluid }, water);
	const double dt = 0.5 * solver.timeStepLimits().critical;
	solver.step(dt); // warm-up: allocates the scratch arrays
	const long rssAfter = residentKiB();

	std::vector<double> rates;
	auto                before = solver.stageSeconds();
	for (int r = 0; r < repeats; ++r) {
		const auto start = std::chrono::steady_clock::now();
		for (int i = 0; i < steps; ++i) solver.step(dt);
		const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
		rates.push_back(n * steps / seconds);
	}
	std::sort(rates.begin(), rates.end());
	const double median  = rates[rates.size() / 2];
	const int    threads = omp_get_max_threads();
	auto         after   = solver.stageSeconds();
	double       total   = 0;
	for (int i = 0; i < static_cast<int>(Stage::Count); ++i) total += after[i] - before[i];
	std::printf("%zu\t%d\t%.4g\t%.4g\t%.0f", n, threads, median, median / threads, 1024.0 * (rssAfter - rssBefore) / n);
	for (int i = 0; i < static_cast<int>(Stage::Count); ++i) std::printf("\t%s=%.1f", stageName(static_cast<Stage>(i)), 100 * (after[i] - before[i]) / total);
	std::printf("\n");
	return 0;
}
