// Regular Cartesian background grid and its nodal fields (doc/theory.md §4).
#pragma once

#include "Types.hpp"

#include <array>
#include <vector>

namespace mpm {

// Faces of the domain box, in this order wherever faces are indexed.
enum class Face { XMin = 0, XMax = 1, YMin = 2, YMax = 3, ZMin = 4, ZMax = 5 };
constexpr int faceCount = 6;
// How messages name face f (0..5) and axis d (0..2).
inline const char* faceName(int f)
{
	static constexpr const char* names[faceCount] = { "xMin", "xMax", "yMin", "yMax", "zMin", "zMax" };
	return names[f];
}
inline char        axisName(int d) { return "xyz"[d]; }

// The grid covers the domain box [lower, upper] plus one padding cell on every side, so that
// GIMP supports (reach h + l_p) of points inside the box always find their nodes.
struct GridGeometry {
	Vec3               origin;   // position of node (0, 0, 0) [m]
	Real               cellSize; // h [m]
	std::array<int, 3> nodes;    // node count per axis
	std::array<int, 3> wallNode; // index of the node plane of the lower walls (1)
	std::array<int, 3> upperWallNode;
	// Periodic axes (theory.md §2.7): node upperWallNode is node wallNode, so the nodes in use along
	// such an axis are wallNode .. upperWallNode − 1 and a stencil index wraps onto them.
	std::array<bool, 3> periodic { false, false, false };

	static GridGeometry forDomain(const Vec3& lower, const Vec3& upper, Real cellSize, const std::array<bool, 3>& periodic = { false, false, false });
	std::size_t         nodeCount() const { return static_cast<std::size_t>(nodes[0]) * nodes[1] * nodes[2]; }
	std::size_t         index(int i, int j, int k) const { return static_cast<std::size_t>(i) + nodes[0] * (static_cast<std::size_t>(j) + static_cast<std::size_t>(nodes[1]) * k); }
	// grid indices (i, j, k) of node I
	std::array<int, 3>  indices(std::size_t I) const
	{
		const std::size_t nx = nodes[0], ny = nodes[1];
		return { static_cast<int>(I % nx), static_cast<int>((I / nx) % ny), static_cast<int>(I / (nx * ny)) };
	}
	// whether node index i along axis d lies on the wall plane of `side` (0 lower, 1 upper), beyond it,
	// or within `inward` nodes inside it; a periodic axis has no walls
	bool                atWall(int d, int side, int i, int inward = 0) const
	{
		return !periodic[d] && (side == 0 ? i <= wallNode[d] + inward : i >= upperWallNode[d] - inward);
	}
	Vec3                nodePosition(int i, int j, int k) const { return origin + cellSize * Vec3(i, j, k); }
	Vec3                lower() const { return nodePosition(wallNode[0], wallNode[1], wallNode[2]); }
	// Node index i along axis d after wrapping a periodic axis onto [wallNode, upperWallNode)
	int wrap(int d, int i) const
	{
		if (!periodic[d]) return i;
		const int cells = upperWallNode[d] - wallNode[d], shifted = (i - wallNode[d]) % cells;
		return wallNode[d] + (shifted < 0 ? shifted + cells : shifted);
	}
	// Length along axis d of node i's support inside the domain box, ∫ N_i dx over the box [m]:
	// h inside, h/2 on a wall plane, 0 beyond the walls.
	Real inDomainSupport(int d, int i) const
	{
		if (periodic[d]) return i >= wallNode[d] && i < upperWallNode[d] ? cellSize : 0; // no walls: every node in use is interior
		if (i < wallNode[d] || i > upperWallNode[d]) return 0;
		return i == wallNode[d] || i == upperWallNode[d] ? cellSize / 2 : cellSize;
	}
	// Volume of node (i, j, k)'s support inside the domain box [m³] (h³ inside, halved per wall plane)
	Real inDomainSupportVolume(int i, int j, int k) const { return inDomainSupport(0, i) * inDomainSupport(1, j) * inDomainSupport(2, k); }
	Vec3 upper() const { return nodePosition(upperWallNode[0], upperWallNode[1], upperWallNode[2]); }
};

// Nodal quantities mapped from the solid points.
struct SolidNode {
	Real mass;         // m^s_I [kg]
	Vec3 momentum;     // P^s_I [kg m s⁻¹]
	Vec3 mixtureForce; // f^m_I: effective stress, solid weight and point loads; pressure and water weight added later [N]
	Real volume;       // V_I = Σ S V_sp, mixture volume [m³]
	Real solidVolume;  // Σ S m_sp/ρs, grain volume [m³]
	Real drag;         // Q_I = Σ S V_sp n² μw/κ [kg s⁻¹]
};

// Nodal quantities mapped from the water points.
struct WaterNode {
	Real mass;          // m^w_I [kg]
	Vec3 momentum;      // P^w_I [kg m s⁻¹]
	Vec3 weight;        // Σ S m_wp b [N]
	Vec3 porousForce;   // Σ V_wp p (n ∇S + S ∇n), the −n∇p force on the water [N]
	Vec3 pressureForce; // f^p_I = Σ V_wp p ∇S, pore-pressure part of the mixture force [N]
	Real volume;        // Σ S V_wp, mixture volume carried by water points [m³] (free-surface detection)
	Real pressureVolume; // Σ S V_wp p [Pa m³]; / volume: the nodal pore pressure (suction-holding surface)
};

// Nodal sums of the current pore pressure (pressure-mode damping, theory.md eq. 4.17b).
struct PressureNode {
	Real pressureVolume; // Σ S V_wp p [Pa m³]
	Real volume;         // Σ S V_wp [m³]
};

// Nodal sums of the MUSL re-map (theory.md eq. 4.12).
struct MomentumNode {
	Vec3 momentum; // Σ S m_p v_p [kg m s⁻¹]
	Real mass;     // Σ S m_p [kg]
};

inline MomentumNode& operator+=(MomentumNode& a, const MomentumNode& b)
{
	a.momentum += b.momentum;
	a.mass += b.mass;
	return a;
}

inline PressureNode& operator+=(PressureNode& a, const PressureNode& b)
{
	a.pressureVolume += b.pressureVolume;
	a.volume += b.volume;
	return a;
}

// Volume-weighted moments of one set's water points in one grid cell, about the cell centre x_c
// (edge pressure smoothing, theory.md eq. 4.17c).
// Free-surface points are left out.
struct PressureCell {
	Real volume;         // Σ V [m³]
	Vec3 offset;         // Σ V (x − x_c) [m⁴]
	Mat3 offsetSquare;   // Σ V (x − x_c)(x − x_c)ᵀ [m⁵]
	Real pressure;       // Σ V p [Pa m³]
	Vec3 pressureOffset; // Σ V p (x − x_c) [Pa m⁴]
};

inline PressureCell& operator+=(PressureCell& a, const PressureCell& b)
{
	a.volume += b.volume;
	a.offset += b.offset;
	a.offsetSquare += b.offsetSquare;
	a.pressure += b.pressure;
	a.pressureOffset += b.pressureOffset;
	return a;
}

// Least-squares linear pressure field p(x) = value + gradient·(x − x_c) around a cell (eq. 4.17c).
struct PressureFit {
	Real value;    // at the cell centre [Pa]
	Vec3 gradient; // [Pa m⁻¹]
};

inline SolidNode& operator+=(SolidNode& a, const SolidNode& b)
{
	a.mass += b.mass;
	a.momentum += b.momentum;
	a.mixtureForce += b.mixtureForce;
	a.volume += b.volume;
	a.solidVolume += b.solidVolume;
	a.drag += b.drag;
	return a;
}
inline WaterNode& operator+=(WaterNode& a, const WaterNode& b)
{
	a.mass += b.mass;
	a.momentum += b.momentum;
	a.weight += b.weight;
	a.porousForce += b.porousForce;
	a.pressureForce += b.pressureForce;
	a.pressureVolume += b.pressureVolume;
	a.volume += b.volume;
	return a;
}

struct GridFields {
	std::vector<SolidNode> solid;
	std::vector<WaterNode> water;
	std::vector<Real>      porosity;         // n_I = 1 − (grain volume)/(mixture volume) [-]
	std::vector<Real>      dragSupport;      // V^w_I/V_I where the drag is limited to the water-sampled support (eq. 4.7b), else 1 [-]
	std::vector<Vec3>      solidVelocity;    // v^s_I at t^n [m s⁻¹]
	std::vector<Vec3>      waterVelocity;    // v^w_I at t^n [m s⁻¹]
	std::vector<Vec3>      solidVelocityNew; // v^s_I at t^{n+1}, then the MUSL remapped v̂^s [m s⁻¹]
	std::vector<Vec3>      waterVelocityNew; // v^w_I at t^{n+1}, then the MUSL remapped v̂^w [m s⁻¹]

	void resize(std::size_t n);
};

} // namespace mpm
