"""The saturated sand pile in a flume: one scene definition (geometry, materials, head history)
shared by the MPM example and, later, the DEM + pore-fluid (PFV) version, which reads the same
numbers instead of copying them.

The source paper's flume, sand and head history are not available (doc: shared formulation §6);
the values below are documented lab-scale choices, not the paper's:

* flume 0.60 m long (x), 0.10 m wide (y); pile 0.12 m high with a 0.10 m crest, a 30° downstream
  slope and a vertical upstream face against the inflow reservoir at x = 0;
* dense quartz sand: ρs = 2650 kg m⁻³, n = 0.40, E = 20 MPa, ν = 0.3, φ = 36°, ψ = 6°, c = 0,
  friction softening to 30° (the critical state) over κ_s = 0.01, the dilatancy fading with it
  (theory.md eq. 7.1b): a brittle dense sand, most of the softening within ~3% plastic shear
  strain; k = 1e-3 m s⁻¹ (medium sand);
* flume base roughened with glued sand: a Coulomb contact with δ = φ = 36°;
* water: ρw = 1000 kg m⁻³, μw = 1e-3 Pa s, Kw lowered to 2.2e8 Pa for speed: Kw/n = 20 E_oed keeps
  the water nearly incompressible for this quasi-static seepage (the formulation asks ≥ 10–100);
* the pile starts saturated throughout, at rest: hydrostatic below the inflow level 0.03 m and held
  by capillary suction above it (the experiment keeps the pile saturated for the same reason);
* head at the inflow face held at 0.03 m for 3 s (the pile settles under gravity), then raised
  linearly to the crest, 0.12 m, over 60 s (1.5 mm/s: the laboratory rate issue 15 names,
  0.03 → 0.12 m over 60 s; the source paper's own rate is not in the text available to us), then
  held for 20 s. Over 60 s the water moves: the pile takes in some
  40 g of water through the inflow face (doc/sandpile.md), which a compressed rise does not give.
  `COMPRESSED` keeps the same rise over 0.3 s (0.05 s settling, 0.35 s hold) for the explicit step,
  whose time step follows the water's wave (the laboratory history would take ≈ 100 h there at
  h = 1 cm); the pore pressures still follow the rise quasi-statically (consolidation time
  L² γw / (k M) ≈ 0.035 s over the 0.3 m flow path, M = 1/(1/E_oed + n/Kw) ≈ 26 MPa), but the
  water itself moves less than a millimetre, and the ratio of drainage time to loading time that
  decides when a dilatant sand fails is 200 times off.
"""
import math
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SandPileScene:
    flume_length: float = 0.60       # [m] along x
    flume_width: float = 0.10        # [m] along y (front and rear walls at y = 0 and y = width)
    flume_height: float = 0.20       # [m] domain height above the base
    pile_height: float = 0.12        # [m]
    crest_length: float = 0.10       # [m] flat top, starting at the inflow face x = 0
    slope_angle: float = math.radians(30)  # [rad] downstream face
    grain_density: float = 2650.0    # ρs [kg m⁻³]
    porosity: float = 0.40           # n0 [-]
    young_modulus: float = 20e6      # E [Pa]
    poisson_ratio: float = 0.3       # ν [-]
    friction_angle: float = math.radians(36)          # φ [rad]
    dilatancy_angle: float = math.radians(6)          # ψ [rad]
    residual_friction_angle: float = math.radians(30)  # φ_r [rad]
    softening_strain: float = 0.01   # κ_s [-]
    base_friction_angle: float = math.radians(36)  # δ [rad] of the flume base (sand glued on it: δ = φ)
    hydraulic_conductivity: float = 1e-3  # k [m s⁻¹]
    water_density: float = 1000.0    # ρw [kg m⁻³]
    water_viscosity: float = 1e-3    # μw [Pa s]
    water_bulk_modulus: float = 2.2e8  # Kw [Pa]
    head_start: float = 0.03         # inflow water level while the pile settles [m]
    head_end: float = 0.12           # inflow water level at the end of the ramp (the crest) [m]
    settle_time: float = 3.0         # head held at head_start from t = 0 [s]
    head_ramp_time: float = 60.0     # duration of the linear rise that follows [s]
    hold_time: float = 20.0          # head held at head_end after the rise [s]
    # Elevation of still water over the whole flume [m], or None (the pile stands in air). With it the
    # pile is submerged: the downstream flume holds still water at this level, the inflow head rises
    # from it, and the model solves the excess pore pressure (engine stillWaterLevel, theory.md eq. 1.9).
    still_water_level: float = None
    # An impermeable, smooth lid on the crest [-]: the model's top at the crest height (domain_height), a contact that
    # holds the crest down (on the semi-implicit step also up: theory.md eq. 2.6b) and keeps the water from leaving through it, so that
    # the seepage leaves through the slope (a submerged crest next to the inflow face is a piping exit
    # otherwise: the face's excess head meets the surface's p = 0 across one cell).
    crest_lid: bool = False

    def domain_height(self):
        """Height of the model's domain above the base [m]: the crest with a crest lid (the lid is
        the domain's top face), else the flume's height."""
        return self.pile_height if self.crest_lid else self.flume_height

    def toe_x(self):
        """x of the downstream toe [m]."""
        return self.crest_length + self.pile_height / math.tan(self.slope_angle)

    def surface_height(self, x):
        """Height of the pile surface above the base at x [m] (0 beyond the toe)."""
        x = np.asarray(x, dtype=float)
        down = self.pile_height - (x - self.crest_length) * math.tan(self.slope_angle)
        return np.where(x <= self.crest_length, self.pile_height, np.clip(down, 0, None))

    def starting_water_table(self, x):
        """The phreatic surface of steady seepage under the starting head [m] at x [m], in Dupuit's
        approximation (Dupuit 1863, Forchheimer 1886; e.g. Harr, Groundwater and Seepage, 1962, §2):
        unconfined flow over the impermeable base from the inflow face (head_start at x = 0) to the
        toe, where the water leaves onto the dry flume (tail water 0): h² = h0² (1 − x/L), L = toe_x,
        independent of the conductivity; below the ground surface (the seepage face near the toe,
        where h would stand above the slope), and none beyond the toe. With still water the table is
        the level (no seepage at the start). This is the state the pile is in once the starting head
        has been held long enough, which the horizontal table at head_start is not: near the toe, where
        the ground lies below head_start, that table puts positive pore pressure on a drained surface,
        and the pile starts draining at an exit gradient above one (git history of doc/sandpile.md)."""
        x = np.asarray(x, dtype=float)
        if self.still_water_level is not None:
            return np.full(x.shape, float(self.still_water_level))
        dupuit = self.head_start * np.sqrt(np.clip(1 - x / self.toe_x(), 0, None))
        return np.minimum(dupuit, self.surface_height(x))

    def probe_points(self, flume_width=None):
        """Pore-pressure probes {name: (x, y, z)} [m] at mid-width (of `flume_width`, default the
        flume's): upstream, at the crest's edge, mid-slope and near the toe, 2 cm (the toe's 1 cm)
        above the base, where the seepage field of the rising head is read in every model."""
        y = 0.5 * (self.flume_width if flume_width is None else flume_width)
        return {"upstream x=0.05": (0.05, y, 0.02), "crest edge x=%.2f" % self.crest_length: (self.crest_length, y, 0.02),
                "mid slope x=0.20": (0.20, y, 0.02), "near toe x=0.27": (0.27, y, 0.01)}

    def head(self, time):
        """Inflow water level [m] at time t [s]: held while settling, raised linearly, then held."""
        r = min(max((time - self.settle_time) / self.head_ramp_time, 0.0), 1.0)
        return self.head_start + r * (self.head_end - self.head_start)

    def duration(self):
        """Settling, rise and hold [s]."""
        return self.settle_time + self.head_ramp_time + self.hold_time

    def intrinsic_permeability(self, gravity):
        """κ = k μw / (ρw |g|) [m²] for the scene's gravity vector [m s⁻²]."""
        return self.hydraulic_conductivity * self.water_viscosity / (self.water_density * float(np.linalg.norm(gravity)))

    def validate(self):
        if not (0 < self.slope_angle < math.pi / 2):
            raise ValueError("slope_angle = %r rad is outside the valid range (0, π/2)" % self.slope_angle)
        if self.toe_x() >= self.flume_length:
            raise ValueError("the pile's toe x = %.3f m lies beyond the flume length %.3f m" % (self.toe_x(), self.flume_length))
        if self.still_water_level is None:
            if not (0 <= self.head_start <= self.head_end <= self.pile_height):
                raise ValueError("heads must satisfy 0 ≤ head_start ≤ head_end ≤ pile_height; got %r, %r, %r m" % (self.head_start, self.head_end, self.pile_height))
        elif not (self.pile_height <= self.still_water_level <= self.head_start <= self.head_end):
            raise ValueError("a submerged pile needs pile_height ≤ still_water_level ≤ head_start ≤ head_end; got %r, %r, %r, %r m"
                             % (self.pile_height, self.still_water_level, self.head_start, self.head_end))
        if not (0 <= self.base_friction_angle < math.pi / 2):
            raise ValueError("base_friction_angle = %r rad is outside the valid range [0, π/2)" % self.base_friction_angle)
        if self.pile_height >= self.flume_height:
            raise ValueError("pile_height = %r m must be below flume_height = %r m" % (self.pile_height, self.flume_height))


DEFAULT = SandPileScene()

# The same scene with the rise compressed 200× (0.05 s settling, 0.3 s rise, 0.35 s hold): for the
# explicit step, which follows the water's wave (module docstring).
COMPRESSED = SandPileScene(settle_time=0.05, head_ramp_time=0.3, hold_time=0.35)

# The same pile submerged 3 cm under still water (the downstream flume full, as behind a weir),
# the inflow reservoir raised from that level by up to one pile height over a laboratory minute
# (2 mm/s), after 1 s at the still level in which the pile settles; real water (Kw = 2.2 GPa: the
# semi-implicit step does not follow the water's wave). Fully saturated from the start, so no
# partially saturated zone forms (the paper's aim in raising the inflow head); no seepage at the
# start, so the 30° slope of a 36° sand stands; the rising head drives seepage out of the slope.
# Measured (doc/sandpile.md): it yields at the limit-equilibrium head as a shallow slide of the
# upper slope, and the crest's upstream corner heaves.
SUBMERGED = SandPileScene(still_water_level=0.15, head_start=0.15, head_end=0.27, settle_time=1.0, head_ramp_time=60.0, hold_time=20.0,
                          water_bulk_modulus=2.2e9)


def pile_points(scene, cell_size, points_per_cell=2):
    """Centres of the lattice points (points_per_cell per cell and axis) inside the pile, and the
    point spacing [m]. Points are kept where their centre lies below the pile surface."""
    scene.validate()
    spacing = cell_size / points_per_cell
    nx = int(round(scene.flume_length / spacing))
    ny = int(round(scene.flume_width / spacing))
    nz = int(round(scene.pile_height / spacing))
    x = spacing * (np.arange(nx) + 0.5)
    y = spacing * (np.arange(ny) + 0.5)
    z = spacing * (np.arange(nz) + 0.5)
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    inside = Z < scene.surface_height(X)
    return np.stack([X[inside], Y[inside], Z[inside]], axis=1), spacing


def pile_section(scene, solid, fluid, gravity, cell_size, point_spacing, davis=True):
    """The pile's 2D section for limit equilibrium (yade_mpm.slope_stability) on the run's current state:
    weights from both phases' point masses, pore pressures from the water points, averaged over the
    flume's width, binned by cell; the sand's peak strength reduced for its non-associated flow by Davis
    (φ = 36°, ψ = 6° → φ* = 31.9°), or with davis=False the peak itself (the upper bound the model's
    skeleton can mobilise before it softens)."""
    from . import slope_stability
    strength = slope_stability.Strength(cohesion=0.0, friction_angle=scene.friction_angle, dilatancy_angle=scene.dilatancy_angle)
    if davis:
        strength = strength.davis()
    solid_mass, water_mass = np.asarray(solid.mass), np.asarray(fluid.mass)
    if scene.still_water_level is not None:
        # submerged (eq. 1.9): buoyant grains, weightless water and excess pore pressures — Bishop's
        # method with effective unit weights, equivalent to the total weights with the still water's
        # pressure on the ground surface
        solid_mass, water_mass = solid_mass * (1 - scene.water_density / scene.grain_density), np.zeros(len(water_mass))
    return slope_stability.section_from_points(solid.pos, solid_mass, fluid.pos, water_mass, fluid.porePressure, gravity,
                                               scene.flume_width, cell_size, strength, direction=1, base_z=0.0,
                                               surface_offset=0.5 * point_spacing)


def limit_equilibrium(scene, solid, fluid, gravity, cell_size, point_spacing, min_depth=None, davis=True, section=None):
    """Bishop's critical circle of the pile's downstream slope on the run's current state (the section of
    pile_section, with davis as there, or `section` if given, built by it); centres over the slope from one
    cell to four pile heights above the base (the toe's slumps as well as deep slides); slip circles no deeper than the
    flume base and at least min_depth deep [m] (default one cell: a thinner slide is below what the
    MPM resolves); with a crest lid, only slides that break through the ground downstream of it (the
    lid's reaction, which holds the crest down against the excess pressure, is not known to the
    method). Returns the slope_stability.CriticalCircle (its .factor is the factor of safety)."""
    from . import slope_stability
    if section is None:
        section = pile_section(scene, solid, fluid, gravity, cell_size, point_spacing, davis)
    height, toe = scene.pile_height, scene.toe_x()
    # centres from one cell above the base (the small circles of a slump at the toe, where the seepage
    # leaves the face: 1-2 cells deep, centres a few cm up) to 4 pile heights (the deep circles), spaced
    # geometrically so that both are searched at the same relative resolution
    return slope_stability.critical_circle(section, np.linspace(scene.crest_length, toe + 0.5 * height, 13),
                                           np.geomspace(cell_size, 4 * height, 12), radii_per_centre=10,
                                           min_depth=cell_size if min_depth is None else min_depth, slice_count=30,
                                           free_ground=(scene.crest_length, math.inf) if scene.crest_lid else None)
