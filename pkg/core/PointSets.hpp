// Material point sets in structure-of-arrays form: one contiguous array per field, so that the
// stages stream through memory and OpenMP splits them by index (doc/theory.md §4).
#pragma once

#include "ShapeFunctions.hpp"
#include "Types.hpp"

#include <array>
#include <string>
#include <vector>

namespace mpm {

// How messages spell the point fields: the C++ member names by default; a binding passes the names
// its users see (e.g. "pos" for position).
struct PointFieldNames {
	const char* position            = "position";
	const char* velocity            = "velocity";
	const char* deformationGradient = "deformationGradient";
	const char* effectiveStress     = "effectiveStress";
	const char* externalForce       = "externalForce";
	const char* volume              = "volume";
};

// One point's 1D stencil weights along x, y, z. Its constructor leaves them unset, so that
// resizing the cache below writes nothing: every entry is filled right after (a value-initialised
// std::array would be zeroed first, a pass over the whole cache in every step).
struct StencilWeights : std::array<Weights1D, 3> {
	StencilWeights() {}
	StencilWeights(const Weights1D& x, const Weights1D& y, const Weights1D& z) : std::array<Weights1D, 3> { x, y, z } {}
};

// Fields every material point carries, whatever its phase.
struct MaterialPointSet {
	std::vector<Vec3> position;   // x_p [m]
	std::vector<Vec3> velocity;   // v_p [m s⁻¹]
	std::vector<Real> mass;       // m_p [kg], constant over a run
	std::vector<Real> volume;     // V_p [m³], current mixture volume represented by the point
	std::vector<Vec3> halfLength; // l_p [m], GIMP half-size of the point's domain per axis
	// Solver scratch, not point data: the 1D stencil weights of every point at its current position
	// (theory.md eq. 3.2), computed once for the stages of a step that share the positions and
	// empty otherwise (TwoPhaseSolver::cacheStencilWeights): valid exactly when it has size() entries.
	std::vector<StencilWeights> stencilWeights;
	// With the cache: the first point whose stencil leaves the grid (or whose position is not finite),
	// found while filling it, or −1 (TwoPhaseSolver::throwIfOutsideGrid reads it instead of a pass of its own).
	long firstOffGrid = -1;

	std::size_t size() const { return position.size(); }
	// Check that every field has size() entries and holds finite, admissible values; throws
	// InvalidParameter naming the set, field (as `names` spells it), point index and value.
	void validate(const std::string& setName, const PointFieldNames& names = {}) const;

protected:
	void resizeCommon(std::size_t n);
};

// Solid skeleton points: carry the effective stress and the porosity of the mixture.
struct SolidPointSet : MaterialPointSet {
	std::vector<Real>   initialVolume;       // V0_p [m³]
	std::vector<Vec3>   initialHalfLength;   // l0_p [m], reference for cpGIMP
	std::vector<Mat3>   deformationGradient; // F_p [-]
	std::vector<Voigt6> effectiveStress;     // σ′_p [Pa], tension-positive, Voigt order
	std::vector<Real>   porosity;            // n_p [-]
	std::vector<Vec3>   externalForce;       // prescribed point load, e.g. a surface traction × area [N]
	std::vector<Real>   plasticShearStrain;  // κ [-], accumulated plastic shear strain (theory.md eq. 7.4)

	void resize(std::size_t n);
	void validate(const std::string& setName, const PointFieldNames& names = {}) const;
};

// Pore-water points: carry the pore pressure; their porosity is interpolated from the solid.
struct WaterPointSet : MaterialPointSet {
	std::vector<Real> porePressure; // p_p [Pa], compression-positive
	std::vector<Real> porosity;     // n_p [-], 1 for free water
	std::vector<Vec3> subscaleFlux; // q′_p [m s⁻¹]: the Darcy flux of the pressure gradient's departure from its cell mean (theory.md eq. 8.6c), 0 unless tracked

	void resize(std::size_t n);
	void validate(const std::string& setName, const PointFieldNames& names = {}) const;
	// Remove the points whose `remove` flag is set, keeping the order of the others; returns the
	// mass removed [kg].
	Real removeWhere(const std::vector<char>& remove);
	// Append a copy of point p (all fields); returns the new point's index.
	std::size_t appendCopyOf(std::size_t p);
};

} // namespace mpm
