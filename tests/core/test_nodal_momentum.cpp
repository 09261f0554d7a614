// The nodal momentum stage (theory.md eqs. 4.8–4.10, 5.2): the [DERIVED] properties of the
// semi-implicit drag, the explicit drag's stability limit, and wall re-solves.
#include "core/Stages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

using namespace mpm;

// One node carrying both phases, with forces and velocities; no walls.
struct OneNode {
	GridFields       fields;
	ConstrainedNodes none;
	OneNode(Real ms, Real mw, Real Q, const Vec3& vs, const Vec3& vw, const Vec3& fSolid, const Vec3& fWater)
	{
		fields.resize(1);
		fields.solid[0]         = SolidNode { ms, ms * vs, fSolid, 1, 0.6, Q };
		fields.water[0]         = WaterNode { mw, mw * vw, Vec3::Zero(), fWater, Vec3::Zero(), 0, 0 };
		fields.solidVelocity[0] = vs;
		fields.waterVelocity[0] = vw;
	}
	void step(Real dt, DragScheme drag) { stages::integrateNodalMomentum(fields, none, dt, drag, 1e-12, 1e-12); }
};

const Vec3 vs0(0.1, -0.2, 0.3), vw0(-0.4, 0.5, 0.05), fs(3, -1, 2), fw(-2, 4, 1);

TEST(SemiImplicitDrag, WithoutDragGivesTheUncoupledUpdates)
{
	OneNode n(2.0, 0.5, 0.0, vs0, vw0, fs, fw);
	n.step(1e-3, DragScheme::SemiImplicit);
	// here f^m = fs (no pressure force or water weight) and f^w = fw: water alone v^w + Δt f^w/m^w,
	// solid by mixture minus water momentum, v^s + Δt (f^m − f^w)/m^s
	EXPECT_LT((n.fields.waterVelocityNew[0] - (vw0 + 1e-3 * fw / 0.5)).norm(), 1e-15);
	EXPECT_LT((n.fields.solidVelocityNew[0] - (vs0 + 1e-3 * (fs - fw) / 2.0)).norm(), 1e-15);
}

TEST(SemiImplicitDrag, InfiniteDragGivesBothPhasesTheMixtureVelocity)
{
	OneNode n(2.0, 0.5, 1e15, vs0, vw0, fs, fw);
	n.step(1e-3, DragScheme::SemiImplicit);
	const Vec3 mixture = (2.0 * vs0 + 0.5 * vw0 + 1e-3 * fs) / 2.5; // (m^s v^s + m^w v^w + Δt f^m)/(m^s + m^w)
	EXPECT_LT((n.fields.waterVelocityNew[0] - mixture).norm(), 1e-9);
	EXPECT_LT((n.fields.solidVelocityNew[0] - mixture).norm(), 1e-9);
}

TEST(SemiImplicitDrag, ConservesMixtureMomentumAndSatisfiesTheImplicitWaterEquation)
{
	for (Real Q : { 0.3, 30.0, 3e4 }) {
		OneNode      n(2.0, 0.5, Q, vs0, vw0, fs, fw);
		const Real   dt = 1e-3;
		n.step(dt, DragScheme::SemiImplicit);
		const Vec3& vs = n.fields.solidVelocityNew[0];
		const Vec3& vw = n.fields.waterVelocityNew[0];
		// mixture: m^s Δv^s + m^w Δv^w = Δt f^m
		EXPECT_LT((2.0 * (vs - vs0) + 0.5 * (vw - vw0) - dt * fs).norm(), 1e-12);
		// water, drag at t^{n+1}: m^w Δv^w = Δt (f^w − Q (v^w+ − v^s+))
		EXPECT_LT((0.5 * (vw - vw0) - dt * (fw - Q * (vw - vs))).norm(), 1e-12);
	}
}

// With drag only, the relative velocity w = v^w − v^s obeys w ← (1 − λΔt) w under explicit drag,
// λ = Q (1/m^w + 1/m^s): stable (|1 − λΔt| < 1) for Δt < 2/λ and amplified beyond (eq. 5.2).
Real relativeAmplification(Real dtOverLimit, DragScheme drag)
{
	const Real ms = 2.0, mw = 0.5, Q = 40.0, lambda = Q * (1 / mw + 1 / ms), dt = dtOverLimit * 2 / lambda;
	OneNode    n(ms, mw, Q, Vec3::Zero(), Vec3(1, 0, 0), Vec3::Zero(), Vec3::Zero());
	Real       w = 1;
	for (int i = 0; i < 50; ++i) {
		n.step(dt, drag);
		n.fields.solidVelocity[0] = n.fields.solidVelocityNew[0];
		n.fields.waterVelocity[0] = n.fields.waterVelocityNew[0];
		n.fields.solid[0].momentum = ms * n.fields.solidVelocity[0];
		n.fields.water[0].momentum = mw * n.fields.waterVelocity[0];
	}
	w = (n.fields.waterVelocity[0] - n.fields.solidVelocity[0]).norm();
	return w;
}

TEST(ExplicitDrag, StableBelowTwoOverLambdaUnstableAbove)
{
	EXPECT_LT(relativeAmplification(0.95, DragScheme::Explicit), 1.0);
	EXPECT_GT(relativeAmplification(1.05, DragScheme::Explicit), 1.0);
	// the semi-implicit drag decays at any step
	EXPECT_LT(relativeAmplification(100.0, DragScheme::SemiImplicit), 1e-6);
}

// One cell on a fixed base (zMin): its grid, the walls' constrained nodes and empty nodal fields.
struct OnFixedBase {
	GridGeometry     g = GridGeometry::forDomain(Vec3::Zero(), Vec3::Ones(), 1.0);
	ConstrainedNodes c;
	GridFields       fields;
	OnFixedBase()
	{
		BoundaryConditions bcs;
		bcs.walls[static_cast<int>(Face::ZMin)] = { SolidWall::Fixed, WaterWall::Free };
		c = ConstrainedNodes::build(g, bcs);
		fields.resize(g.nodeCount());
	}
};

TEST(Walls, HeldSolidComponentReSolvesTheWaterWithDragToIt)
{
	OnFixedBase       cell;
	GridGeometry&     g = cell.g;
	ConstrainedNodes& c = cell.c;
	GridFields&       fields = cell.fields;
	const std::size_t I = g.index(1, 1, 1); // on the base wall
	const Real        Q = 7, mw = 0.5, dt = 1e-2;
	fields.solid[I]     = SolidNode { 2.0, 2.0 * vs0, fs, 1, 0.6, Q };
	fields.water[I]     = WaterNode { mw, mw * vw0, Vec3::Zero(), fw, Vec3::Zero(), 0, 0 };
	fields.solidVelocity[I] = vs0;
	fields.waterVelocity[I] = vw0;
	stages::integrateNodalMomentum(fields, c, dt, DragScheme::SemiImplicit, 1e-12, 1e-12);
	EXPECT_TRUE(fields.solidVelocityNew[I].isZero());
	const Vec3 expected = (mw / dt * vw0 + fw) / (mw / dt + Q); // water dragged against a held skeleton
	EXPECT_LT((fields.waterVelocityNew[I] - expected).norm(), 1e-14);
}

// A dry node on a frictional base (eq. 2.6): mass m, old velocity v, force f; returns the new velocity.
Vec3 contactUpdate(const Vec3& v, const Vec3& f, Real mu, SolidWall sideWall = SolidWall::Free)
{
	GridGeometry       g = GridGeometry::forDomain(Vec3::Zero(), Vec3::Ones(), 1.0);
	BoundaryConditions bcs;
	bcs.walls[static_cast<int>(Face::ZMin)]          = { SolidWall::Frictional, WaterWall::Free };
	bcs.walls[static_cast<int>(Face::ZMin)].friction = mu;
	bcs.walls[static_cast<int>(Face::XMin)]          = { sideWall, WaterWall::Free };
	ConstrainedNodes c = ConstrainedNodes::build(g, bcs);
	GridFields       fields;
	fields.resize(g.nodeCount());
	const std::size_t I     = g.index(1, 1, 1); // on the base, and on the xMin wall
	const Real        m     = 2;
	fields.solid[I]         = SolidNode { m, m * v, f, 1, 0.6, 0 };
	fields.solidVelocity[I] = v;
	stages::integrateNodalMomentum(fields, c, 0.1, DragScheme::SemiImplicit, 1e-12, 1e-12);
	return fields.solidVelocityNew[I];
}

TEST(FrictionalWall, PressedNodeSlidesWithTheCoulombImpulseOrSticks)
{
	// N' = 10 N into the base; trial tangential velocity (0.3, 0.4) + 0.1/2 (6, 8) = (0.6, 0.8), |v_t| = 1
	const Vec3 v(0.3, 0.4, 0), f(6, 8, -10);
	const Vec3 sliding = contactUpdate(v, f, 0.5); // μ N' Δt/m = 0.25: |v_t| 1 → 0.75, same direction
	EXPECT_LT((sliding - Vec3(0.45, 0.6, 0)).norm(), 1e-14);
	EXPECT_TRUE(contactUpdate(v, f, 2.5).isZero()); // μ N' Δt/m = 1.25 ≥ |v_t|: sticks
}

TEST(FrictionalWall, LetsGoOnlyWhatIsPulledOffAndMovesOff)
{
	const Vec3 pulledOff = contactUpdate(Vec3(0.1, 0, 0.2), Vec3(0, 0, 4), 0.5); // free: v + Δt f/m, no friction
	EXPECT_LT((pulledOff - Vec3(0.1, 0, 0.4)).norm(), 1e-14);
	const Vec3 approaching = contactUpdate(Vec3(0.1, 0, -0.5), Vec3(0, 0, 4), 0.5); // v_z + Δt f_z/m = −0.3: held
	EXPECT_LT((approaching - Vec3(0.1, 0, 0)).norm(), 1e-14);                     // N' = 0: no friction either
	// on the edge with a fixed wall the node is held for good, whatever pulls it
	EXPECT_TRUE(contactUpdate(Vec3(0.1, 0, 0.2), Vec3(0, 0, 4), 0.5, SolidWall::Fixed).isZero());
}

// The same contact as a smooth lid on the top face (zMax 'frictional', μ = 0; the sand pile's crest
// lid): it holds a node the soil presses up against it and lets go of one whose weight pulls it
// down, as a lid resting on a crest that may settle away from it.
TEST(FrictionalWall, ASmoothLidHoldsWhatPressesUpAndLetsGoWhatFalls)
{
	GridGeometry       g = GridGeometry::forDomain(Vec3::Zero(), Vec3::Ones(), 1.0);
	BoundaryConditions bcs;
	bcs.walls[static_cast<int>(Face::ZMax)] = { SolidWall::Frictional, WaterWall::Impermeable };
	ConstrainedNodes c = ConstrainedNodes::build(g, bcs);
	auto             update = [&](const Vec3& v, const Vec3& f) {
		GridFields fields;
		fields.resize(g.nodeCount());
		const std::size_t I     = g.index(1, 1, g.upperWallNode[2]);
		const Real        m     = 2;
		fields.solid[I]         = SolidNode { m, m * v, f, 1, 0.6, 0 };
		fields.solidVelocity[I] = v;
		stages::integrateNodalMomentum(fields, c, 0.1, DragScheme::SemiImplicit, 1e-12, 1e-12);
		return Vec3(fields.solidVelocityNew[I]);
	};
	const Vec3 pressedUp = update(Vec3(0.1, 0, 0.05), Vec3(0, 0, 4)); // heave: normal held, the tangential free (μ = 0)
	EXPECT_LT((pressedUp - Vec3(0.1, 0, 0)).norm(), 1e-14);
	const Vec3 falling = update(Vec3(0.1, 0, -0.1), Vec3(0, 0, -4)); // settling away: v + Δt f/m
	EXPECT_LT((falling - Vec3(0.1, 0, -0.3)).norm(), 1e-14);
}

// The release ratio of the inertia scaling (eq. 4.8c) counts the skeleton's free motion only: the
// velocity a wall zeroes at its nodes (the interior's velocity mapped onto them, e.g. a crest creeping
// up against a lid) is the wall's hold, not inertia — it released α = 100 in the lidded sand pile at
// 4.5 s while nothing accelerated. Two nodes of mass 1 (scaled by α = 100) on a fixed base, Δt = 0.01 s,
// g = 10: one on the base moving down 0.001 m/s before its hold, one above accelerating by 0.1 m/s
// sideways: R = α |m Δv| / (Δt g Σ α m) = 100 · 0.1 / (0.01 · 10 · 2) = 50 from the free one alone.
TEST(InertiaRelease, CountsTheFreeMotionNotTheWallsHold)
{
	OnFixedBase       cell;
	GridGeometry&     g = cell.g;
	ConstrainedNodes& c = cell.c;
	GridFields&       fields = cell.fields;
	const std::size_t onBase = g.index(1, 1, 1), above = g.index(1, 1, 2);
	for (std::size_t I : { onBase, above }) fields.solid[I].mass = 100; // α m
	fields.solidVelocity[onBase]    = Vec3(0, 0, -0.001);
	fields.solidVelocityNew[onBase] = Vec3::Zero(); // held by the base
	fields.solidVelocity[above]     = Vec3::Zero();
	fields.solidVelocityNew[above]  = Vec3(0.1, 0, 0);
	std::vector<std::array<bool, 3>> held(c.node.size(), { false, false, false });
	held[c.positionOf[onBase]] = { true, true, true };
	EXPECT_NEAR(stages::skeletonInertiaRatio(fields, c, held, 0.01, 10, 100, 1e-12), 50, 1e-12);
	// a node the wall does not hold this step (a contact that let go) counts whole
	held[c.positionOf[onBase]] = { false, false, false };
	EXPECT_NEAR(stages::skeletonInertiaRatio(fields, c, held, 0.01, 10, 100, 1e-12), 100 * Vec3(0.1, 0, -0.001).norm() / (0.01 * 10 * 2), 1e-12);
}

} // namespace
