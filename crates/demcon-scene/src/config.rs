//! The RON scene schema (file-facing `…Config` types). Only this crate knows RON; the
//! conversion to the lower crates' plain types lives in `convert.rs`.
//!
//! Every struct denies unknown fields, so a misspelt field is an error with its line.

use serde::{Deserialize, Serialize};

/// A whole scene: which packing, which contacts and surfaces, which materials and phases,
/// which physics with which boundary conditions and solver, and which outputs.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// Free-text name, copied into `summary.json`.
    #[serde(default)]
    pub name: String,
    /// Seed of every random choice (packing, inclusion placement).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Where the particles come from.
    pub packing: PackingConfig,
    /// Keep only the particles whose sphere lies inside this region (e.g. a grooved cylinder).
    #[serde(default)]
    pub carve: Option<RegionConfig>,
    /// Which particles `carve` keeps.
    #[serde(default)]
    pub carve_rule: CarveRuleConfig,
    /// How contacts are found.
    #[serde(default)]
    pub contacts: ContactsConfig,
    /// Transmission-surface model of the thermal network.
    #[serde(default)]
    pub surface: SurfaceConfig,
    /// Materials; the first is the matrix (phase 0) unless phases say otherwise.
    pub materials: Vec<MaterialConfig>,
    /// Phase assignments applied in order on top of phase 0.
    #[serde(default)]
    pub phases: Vec<PhaseConfig>,
    /// How `phases` treat the particles their interfaces cut. `None` (the default): `Segment`
    /// with an `Image` phase, else `Conforming` when every network of the scene is the Laguerre
    /// cells' (the cells then follow the surfaces), `Centre` with the contact models.
    #[serde(default)]
    pub phase_rule: Option<PhaseRuleConfig>,
    /// Conductivity of contacts between two phases.
    #[serde(default)]
    pub interface: InterfaceConfig,
    /// Interface resistances between pairs of materials (Kapitza): unlisted pairs stay perfect.
    #[serde(default)]
    pub interfaces: Vec<InterfaceResistanceConfig>,
    /// Boundary resistances between the grains of one material: every contact (Laguerre
    /// facet) between two particles wholly of that material — each particle a grain — carries
    /// the series resistance 1/(h S) (and r/S electric), as an interface does.
    #[serde(default)]
    pub grain_boundaries: Vec<GrainBoundaryConfig>,
    /// Crack surfaces cutting the contacts their segment crosses (open or filled).
    #[serde(default)]
    pub cracks: Vec<CrackConfig>,
    /// Regions whose contacts' conductances are scaled by a factor in (0, 1].
    #[serde(default)]
    pub damage: Vec<DamageConfig>,
    /// Broken bonds imported from a mechanical DEM run (particle index pairs).
    #[serde(default)]
    pub cut_contacts: Option<CutContactsConfig>,
    /// What to do with particle clusters connected to no fixed value.
    #[serde(default)]
    pub floating: FloatingConfig,
    /// The linear solver of every steady, implicit and electric solve.
    #[serde(default)]
    pub linear_solver: LinearSolverConfig,
    /// Heat conduction (omit for a pure electric scene).
    #[serde(default)]
    pub thermal: Option<ThermalConfig>,
    /// Electric conduction and Joule heating (omit for a pure thermal scene).
    #[serde(default)]
    pub electric: Option<ElectricConfig>,
    /// What to write.
    #[serde(default)]
    pub outputs: OutputsConfig,
}

fn default_seed() -> u64 {
    1
}

/// The linear solver (`linear_solver: (method: Auto, rel_tol: 1e-10)`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LinearSolverConfig {
    /// Method.
    #[serde(default)]
    pub method: LinearMethodConfig,
    /// Relative residual ‖b − Ax‖/‖b‖ to reach, in [1e-15, 1e-2] (iterative methods). A
    /// solve that stagnates at round-off above it is accepted and reported when the residual
    /// is within what the arithmetic can reach (`attainable` in the solver report).
    #[serde(default = "default_rel_tol")]
    pub rel_tol: f64,
    /// Most iterations, in [1, 10⁷].
    #[serde(default = "default_max_iter")]
    pub max_iter: usize,
}

impl Default for LinearSolverConfig {
    fn default() -> Self {
        Self {
            method: LinearMethodConfig::Auto,
            rel_tol: default_rel_tol(),
            max_iter: default_max_iter(),
        }
    }
}

fn default_rel_tol() -> f64 {
    1e-10
}

fn default_max_iter() -> usize {
    200_000
}

/// Linear-solver method.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
pub enum LinearMethodConfig {
    /// MIC-preconditioned CG below 10⁴ unknowns, multigrid-preconditioned CG above.
    #[default]
    Auto,
    /// Multigrid-preconditioned CG.
    Multigrid,
    /// MIC (modified incomplete Cholesky) preconditioned CG.
    Mic,
    /// Jacobi-preconditioned CG.
    Jacobi,
    /// Direct sparse Cholesky (to ~10⁵ unknowns).
    Cholesky,
    /// PETSc's multigrid-preconditioned CG over MPI (`docs/distributed.md`): what
    /// `demcon run --distributed` sets; needs a demcon built with `--features petsc`.
    Distributed,
}

/// Where the particles come from.
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum PackingConfig {
    /// Grow a Lubachevsky–Stillinger packing.
    Generate {
        /// The container.
        container: ContainerConfig,
        /// Number of particles.
        count: usize,
        /// Target volume fraction.
        phi: f64,
        /// Radius standard deviation / mean (0 = monodisperse).
        #[serde(default = "default_cov")]
        radius_cov: f64,
        /// Truncation of the Gaussian radii, as ratios (min, max) to the mean.
        #[serde(default)]
        radius_range: Option<(f64, f64)>,
        /// Accept a packing that stopped short of `phi` (jammed or out of budget).
        #[serde(default)]
        allow_short: bool,
    },
    /// Read a plain-text `x y z r` file (relative paths are relative to the scene file).
    File {
        /// The file.
        path: String,
        /// The container, if the file's header does not give it.
        #[serde(default)]
        container: Option<ContainerConfig>,
    },
    /// Copies of a periodic packing (generated or read), `repeat` = (nx, ny, nz) times along
    /// x, y and z: a large periodic packing at the cost of a small one. The local structure
    /// is the original's exactly; the structure repeats every original period (see
    /// `docs/packing.md`).
    Tile {
        /// The periodic packing to copy.
        packing: Box<PackingConfig>,
        /// Copies along x, y and z (each ≥ 1).
        repeat: (usize, usize, usize),
        /// Turn the tiled box's faces into walls (a `Box` container of the same size) instead
        /// of keeping it periodic: the copies are cut at the faces, each sphere belonging to the
        /// box its centre lies in, and its Laguerre cell clipped there (as carving with the
        /// `Centre` rule does), so there is no wall layering and the faces can carry boundary
        /// conditions. Needs `surface: Laguerre` (spheres cross the faces).
        #[serde(default)]
        walls: bool,
    },
    /// Particles handed over in memory by a program (the Python package's
    /// `demcon.Scene(..., packing=p)` and `demcon.homogenize`, or [`crate::Scene::with_particles`]):
    /// a scene file cannot give them, it reads a packing with `File`.
    Given {
        /// Number of particles handed over.
        count: usize,
        /// Their container.
        container: ContainerConfig,
    },
}

fn default_cov() -> f64 {
    0.3
}

/// Which particles a carving keeps.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
pub enum CarveRuleConfig {
    /// Spheres lying wholly inside the region: the kept solid stops a fraction of a radius
    /// inside every cut surface (a thin section comes out too thin).
    #[default]
    WholeSphere,
    /// Particles whose centre lies inside: their representative cells tile the region on
    /// average (the unbiased cut of a homogeneous packing; spheres may protrude).
    Centre,
}

/// How a phase assignment treats the particles cut by its region's boundary.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
pub enum PhaseRuleConfig {
    /// A particle takes the phase of its centre: the interface is resolved to a particle
    /// size.
    Centre,
    /// A particle cut by the interface (|signed distance of its centre| < R_p) keeps the
    /// phase of its centre and becomes a laminate of the two phases: its volume fraction in
    /// each (exact for spheres, a plane cut otherwise), the interface normal, and the
    /// conductivity tensor λ_∥ (I − n nᵀ) + λ_⊥ n nᵀ (arithmetic along the interface,
    /// harmonic across it); heat capacity ρc mixes arithmetically.
    Laminate,
    /// As `Laminate` for volumes and capacities, but each half-bond (centre to mid-branch)
    /// is the series mix of the part of its segment on either side of the interface (a
    /// plane at the particle): branches along the interface see the centre's phase.
    Segment,
    /// The Laguerre cells follow the phases' surfaces (`Spheres`, `Inclusions`,
    /// `Region(Sphere(..))` and the faces of `Region(Box(..))`): seed pairs mirrored across
    /// each surface put facets on it, the packing's particles next to it give way, and every
    /// cell is of one phase (every network `Laguerre`; other regions are assigned by centre).
    /// The default with the Laguerre cells.
    Conforming,
}

/// A container (m). A box spans `[0, size]`; a cylinder is along z from z = 0 with its axis at
/// x = y = 0; a sphere is centred at the origin.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
pub enum ContainerConfig {
    /// Box with hard walls.
    Box {
        /// Edge lengths (m).
        size: (f64, f64, f64),
    },
    /// Cylinder along z.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// Sphere centred at the origin.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// Periodic box.
    Periodic {
        /// Periods (m).
        size: (f64, f64, f64),
    },
}

/// A coordinate axis.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
pub enum AxisConfig {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
}

/// A region of space (m).
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum RegionConfig {
    /// Axis-aligned box.
    Box {
        /// Lower corner (m).
        min: (f64, f64, f64),
        /// Upper corner (m).
        max: (f64, f64, f64),
    },
    /// Cylinder from `base` along `axis`.
    Cylinder {
        /// Centre of the start cap (m).
        base: (f64, f64, f64),
        /// Axis direction.
        axis: AxisConfig,
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// Ball.
    Sphere {
        /// Centre (m).
        centre: (f64, f64, f64),
        /// Radius (m).
        radius: f64,
    },
    /// First minus second.
    Difference(Box<RegionConfig>, Box<RegionConfig>),
    /// Any of.
    Union(Vec<RegionConfig>),
    /// All of.
    Intersection(Vec<RegionConfig>),
}

/// How contacts are found: give `coordination` (target mean Z, the gap tolerance is found by
/// bisection) or `tolerance` (gap ≤ tolerance·(R_p + R_q)), not both. Default: Z = 7.5.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactsConfig {
    /// Target mean coordination number.
    #[serde(default)]
    pub coordination: Option<f64>,
    /// Relative gap tolerance.
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// The calibration constant C_t.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
pub enum CtConfig {
    /// Calibrate on this packing first (Haddad §2.1: flux on top, fixed temperature below).
    Auto,
    /// Use this value.
    Value(f64),
}

/// Transmission-surface model.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
pub enum SurfaceConfig {
    /// S = C_t π R_m² (Haddad 2021).
    Calibrated {
        /// The constant.
        c_t: CtConfig,
    },
    /// S = √(α(n_p) R_p² α(n_q) R_q²) (Terreros, Hubert 2017).
    TerrerosAlpha,
    /// S = the facet the Laguerre (power) cells of the two particles share, with the centre
    /// line split where the facet crosses it; the cells replace the contacts (`contacts` is
    /// then unused) and give each particle its volume. Exact for a linear field (no
    /// calibration, no bias in a homogeneous body); walls are the cells' faces.
    Laguerre,
}

/// The recommended model is the default: exact in a homogeneous body, no calibration
/// (docs/scenes.md, "Defaults").
impl Default for SurfaceConfig {
    fn default() -> Self {
        SurfaceConfig::Laguerre
    }
}

/// A material (SI units).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Name used by phases and messages.
    pub name: String,
    /// λ (W/(m·K)) at `conductivity_ref_temp`.
    pub conductivity: f64,
    /// β_λ (1/K) in λ(T) = λ0 (1 + β_λ (T − T_λ)); 0 (the default): constant. A steady solve
    /// iterates to it (`thermal.nonlinear_iterations`), a transient keeps the conductances of
    /// the initial state in its matrix and the rest as sources at each step's temperatures.
    #[serde(default)]
    pub conductivity_temp_coeff: f64,
    /// T_λ (°C) of the conductivity.
    #[serde(default = "default_ref_temp")]
    pub conductivity_ref_temp: f64,
    /// λ(T) as a table `[(T, λ), …]` (°C, W/(m·K)), linear between points, held beyond the
    /// first and last; replaces `conductivity_temp_coeff` (`conductivity` stays the reference
    /// a tensor is scaled from, and what a homogenisation uses).
    #[serde(default)]
    pub conductivity_table: Option<Vec<(f64, f64)>>,
    /// An anisotropic conductivity replacing `conductivity` in conduction (λ(T) scales it):
    /// `Transverse(axis: (0.0, 0.0, 1.0), along: 10.0, across: 1.0)` or `Full(((kxx, kxy, kxz),
    /// (kyx, kyy, kyz), (kzx, kzy, kzz)))` (W/(m·K), symmetric positive definite). Each bond
    /// takes eᵀ K e along its direction e: exact where the cells are K-orthogonal (a lattice
    /// along the tensor's axes), an error otherwise (docs/heterogeneous.md).
    #[serde(default)]
    pub conductivity_tensor: Option<ConductivityTensorConfig>,
    /// The tensor is given in each shape's own frame: its z axis along the shape's axis (a
    /// fibre that conducts along itself: `Transverse(axis: (0.0, 0.0, 1.0), …)`). For the
    /// material of a `Shapes` or `RandomShapes` phase; particles in no shape keep the scene's
    /// axes.
    #[serde(default)]
    pub tensor_in_shape_frame: bool,
    /// ρ_c (kg/m³).
    pub density: f64,
    /// c (J/(kg·K)).
    pub specific_heat: f64,
    /// ρ_e (Ω·m), needed by electric scenes.
    #[serde(default)]
    pub resistivity: Option<f64>,
    /// β (1/K) in ρ_e(T) = ρ_e0 (1 + β (T − T_ref)).
    #[serde(default)]
    pub resistivity_temp_coeff: f64,
    /// T_ref (°C) of the resistivity.
    #[serde(default = "default_ref_temp")]
    pub resistivity_ref_temp: f64,
}

/// An anisotropic conductivity tensor.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
pub enum ConductivityTensorConfig {
    /// Transversely isotropic: `along` (W/(m·K)) along `axis` (any length ≠ 0), `across`
    /// normal to it.
    Transverse {
        /// The axis.
        axis: (f64, f64, f64),
        /// λ∥ (W/(m·K)), > 0.
        along: f64,
        /// λ⊥ (W/(m·K)), > 0.
        across: f64,
    },
    /// A full tensor, by rows (W/(m·K)).
    Full((Row3, Row3, Row3)),
}

/// A row of three numbers.
pub type Row3 = (f64, f64, f64);

fn default_ref_temp() -> f64 {
    20.0
}

/// A phase assignment.
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum PhaseConfig {
    /// Particles whose centre lies in `region` get `material`.
    Region {
        /// Material name.
        material: String,
        /// The region.
        region: RegionConfig,
    },
    /// Monodisperse non-overlapping spherical inclusions placed by the LS algorithm in the
    /// container's bounding box (Haddad §5).
    Inclusions {
        /// Material name.
        material: String,
        /// Inclusion volume fraction f.
        fraction: f64,
        /// Box edge / inclusion diameter (6 in the paper).
        size_ratio: f64,
    },
    /// Spherical inclusions at given centres, to reproduce a microstructure exactly:
    /// `Spheres(material: "silica", radius: 1e-3, centres: [(x, y, z), ...])` in metres. In a
    /// periodic container their periodic images count.
    Spheres {
        /// Material name.
        material: String,
        /// Radius of every sphere (m).
        radius: f64,
        /// Centres (m), inside the container's bounding box.
        centres: Vec<(f64, f64, f64)>,
    },
    /// Spheroids and cylinders at given places, listed and/or read from `file`:
    /// `Shapes(material: "fibre", shapes: [Spheroid(centre: (x, y, z), axis: (0, 0, 1), a: 5e-4,
    /// b: 1e-4), Cylinder(centre: (…), axis: (…), radius: 1e-4, length: 2e-3, ends: Round)])`, in
    /// metres. Centres inside the container's bounding box; in a walled container each shape
    /// wholly inside it; in a periodic container their periodic images count. Followed by
    /// conforming cells (`Conforming`, the default with the Laguerre cells), or cut by their
    /// level set under the `Segment`, `Laminate` or `Centre` rule.
    Shapes {
        /// Material name.
        material: String,
        /// The shapes.
        #[serde(default)]
        shapes: Vec<ShapeConfig>,
        /// A text file of more shapes (relative to the scene file), one per line,
        /// whitespace- or comma-separated, `#` comments: `spheroid x y z ux uy uz a b`, or
        /// `cylinder x y z ux uy uz radius length flat|round` (m).
        #[serde(default)]
        file: Option<String>,
        /// The shapes must not touch or overlap (checked before packing; a pair that does is
        /// refused by index). By default they may: the phase is their union.
        #[serde(default)]
        disjoint: bool,
    },
    /// Shapes placed at random (random sequential addition with rattling) to a volume fraction
    /// of the container (a `Box`, shapes wholly inside, or `Periodic`), seeded by `seed`:
    /// `RandomShapes(material: "fibre", shape: Cylinder(ends: Round), aspect: 10, radius: 5e-5,
    /// fraction: 0.2, min_gap: 1e-6, orientation: Isotropic)`.
    RandomShapes {
        /// Material name.
        material: String,
        /// Spheroids or cylinders.
        shape: ShapeKindConfig,
        /// Length over diameter (spheroid: a / b), > 0 (< 1: platelets).
        aspect: f64,
        /// Mean radius across the axis (m), > 0.
        radius: f64,
        /// Spread of the radius (std / mean of a Gaussian truncated at ± 2.5 σ), ≥ 0; the aspect
        /// is kept.
        #[serde(default)]
        radius_cov: f64,
        /// Target volume fraction of the shapes in the container, in (0, 1).
        fraction: f64,
        /// Smallest distance between two shapes (m), ≥ 0.
        #[serde(default)]
        min_gap: f64,
        /// Axes: `Isotropic` (default), `Aligned((x, y, z))`, or `Tensor(((a11, a12, a13), (a21,
        /// a22, a23), (a31, a32, a33)))`, the second moment ⟨u uᵀ⟩ (symmetric, trace 1).
        #[serde(default)]
        orientation: OrientationConfig,
    },
    /// Phases from a labelled 3-D image: `Image(path: "scan.npy", voxel: 2e-6, labels: [(0,
    /// "epoxy"), (1, "glass")])`. Each label's voxels take its material (a smoothed level set
    /// through the voxel faces, cut under the `Segment` rule, the default with images). The image
    /// must cover the container's box; every label in it needs a material.
    Image {
        /// The image (relative to the scene file): `.npy` (a 3-D integer array, axes x, y, z),
        /// `.tif`/`.tiff` (one grey page per z-slice, x along the rows) or `.raw` (with `dims`
        /// and `dtype`, x fastest, little-endian).
        path: String,
        /// Edge of a voxel (m), > 0.
        voxel: f64,
        /// The image's lower corner (m).
        #[serde(default)]
        origin: (f64, f64, f64),
        /// Label → material name, for every label the image holds.
        labels: Vec<(i64, String)>,
        /// Voxels along x, y, z of a `.raw` image.
        #[serde(default)]
        dims: Option<(usize, usize, usize)>,
        /// Element type of a `.raw` image: `u8`, `u16`, `u32`, `i8`, `i16` or `i32`.
        #[serde(default)]
        dtype: Option<String>,
    },
}

impl PhaseConfig {
    /// The materials the entry gives its particles.
    pub fn materials(&self) -> Vec<&str> {
        match self {
            Self::Region { material, .. }
            | Self::Inclusions { material, .. }
            | Self::Spheres { material, .. }
            | Self::Shapes { material, .. }
            | Self::RandomShapes { material, .. } => vec![material.as_str()],
            Self::Image { labels, .. } => labels.iter().map(|(_, m)| m.as_str()).collect(),
        }
    }
}

/// One shaped inclusion (m).
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum ShapeConfig {
    /// A spheroid: semi-axis `a` along `axis`, `b` across (prolate when a > b, oblate when a < b).
    Spheroid {
        /// Centre (m).
        centre: (f64, f64, f64),
        /// Direction of the symmetry axis (any non-zero length).
        axis: (f64, f64, f64),
        /// Semi-axis along `axis` (m), > 0.
        a: f64,
        /// Semi-axis across `axis` (m), > 0.
        b: f64,
    },
    /// A circular cylinder of total length `length` (tip to tip, caps included) along `axis`.
    Cylinder {
        /// Centre (m).
        centre: (f64, f64, f64),
        /// Direction of the axis (any non-zero length).
        axis: (f64, f64, f64),
        /// Radius (m), > 0.
        radius: f64,
        /// Total length (m), > 0; ≥ 2 radius with round ends.
        length: f64,
        /// `Flat` or `Round` (hemispherical) ends; `Round` by default.
        #[serde(default)]
        ends: EndsConfig,
    },
}

/// The ends of a cylinder.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
pub enum EndsConfig {
    /// Flat discs.
    Flat,
    /// Hemispheres (a spherocylinder).
    #[default]
    Round,
}

/// The kind of shape [`PhaseConfig::RandomShapes`] places.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
pub enum ShapeKindConfig {
    /// Spheroids.
    Spheroid,
    /// Cylinders.
    Cylinder {
        /// `Flat` or `Round` ends; `Round` by default.
        #[serde(default)]
        ends: EndsConfig,
    },
}

/// A 3 × 3 matrix by rows.
pub type Rows3 = ((f64, f64, f64), (f64, f64, f64), (f64, f64, f64));

/// How [`PhaseConfig::RandomShapes`] draws the axes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, Serialize)]
pub enum OrientationConfig {
    /// Uniform on the sphere.
    #[default]
    Isotropic,
    /// Every axis along this direction.
    Aligned((f64, f64, f64)),
    /// Drawn so that ⟨u uᵀ⟩ is this tensor (rows; symmetric, eigenvalues ≥ 0, trace 1).
    Tensor(Rows3),
}

/// An imperfect interface between two materials:
/// `(between: ("epoxy", "silica"), conductance: 1.0e6, electric_resistance: Some(1.0e-9))`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InterfaceResistanceConfig {
    /// The two material names.
    pub between: (String, String),
    /// Thermal interface conductance h (W/(m²·K)), > 0: series resistance 1/(h S).
    pub conductance: f64,
    /// Electric interface resistance r_c (Ω·m²), ≥ 0: series resistance r_c/S; `None`:
    /// electrically perfect.
    #[serde(default)]
    pub electric_resistance: Option<f64>,
}

/// The boundary between two grains (particles) of one material.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GrainBoundaryConfig {
    /// The material.
    pub material: String,
    /// Thermal boundary (Kapitza) conductance h (W/(m²·K)), > 0.
    pub conductance: f64,
    /// Electric boundary resistance r (Ω·m²), ≥ 0; `None`: electrically perfect.
    #[serde(default)]
    pub electric_resistance: Option<f64>,
    /// Spread of h over the facets: the coefficient of variation (≥ 0) of a log-normal factor
    /// of mean 1, drawn per facet from the scene's `seed` (the electric resistance takes the
    /// inverse factor); `None`: the same h everywhere.
    #[serde(default)]
    pub spread: Option<f64>,
}

/// A crack surface: `Disc(centre, normal, radius)` or `Polygon(points)`; open (insulating) by
/// default, filled with `gap_conductance: Some(h)` (W/(m²·K)).
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum CrackConfig {
    /// A flat disc (penny crack).
    Disc {
        /// Centre (m).
        centre: (f64, f64, f64),
        /// Normal (any non-zero length).
        normal: (f64, f64, f64),
        /// Radius (m), > 0.
        radius: f64,
        /// Filled crack: conductance per area (W/(m²·K)), > 0; `None`: open, insulating.
        #[serde(default)]
        gap_conductance: Option<f64>,
        /// Filled crack: electric resistance per area (Ω·m²), ≥ 0 (needed by an electric scene).
        #[serde(default)]
        gap_electric_resistance: Option<f64>,
    },
    /// A plane polygon (vertices in order, at least 3).
    Polygon {
        /// Vertices (m).
        points: Vec<(f64, f64, f64)>,
        /// Filled crack: conductance per area (W/(m²·K)), > 0; `None`: open, insulating.
        #[serde(default)]
        gap_conductance: Option<f64>,
        /// Filled crack: electric resistance per area (Ω·m²), ≥ 0 (needed by an electric scene).
        #[serde(default)]
        gap_electric_resistance: Option<f64>,
    },
}

/// A damaged region: `(region: Sphere(..), factor: 0.3)`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DamageConfig {
    /// The region; a contact is in it by the midpoint of its branch.
    pub region: RegionConfig,
    /// Factor on the conductances (both physics), in (0, 1].
    pub factor: f64,
}

/// Broken bonds to cut.
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum CutContactsConfig {
    /// A text file (relative to the scene) of particle index pairs, one pair per line
    /// (`i j` or `i, j`, 0-based, in the packing's order before carving); `#` starts a comment.
    File(String),
}

/// Contact conductivity between two phases.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize)]
pub enum InterfaceConfig {
    /// 2 λ_a λ_b / (λ_a + λ_b) (Haddad eq. 24, perfect interface).
    #[default]
    Harmonic,
    /// (λ_a + λ_b)/2 (overestimates, kept for comparison).
    Arithmetic,
}

/// Clusters connected to no fixed value.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize)]
pub enum FloatingConfig {
    /// Exclude them from the solve with a warning (their values are reported as missing).
    #[default]
    Exclude,
    /// Fail the run.
    Fail,
}

/// A face of the container.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
pub enum FaceConfig {
    /// x = min.
    XMin,
    /// x = max.
    XMax,
    /// y = min.
    YMin,
    /// y = max.
    YMax,
    /// z = min.
    ZMin,
    /// z = max.
    ZMax,
    /// Curved wall of a cylinder or sphere.
    Outer,
    /// The surface of the carving region (`carve`) of a carved body, under `surface: Laguerre`:
    /// a wall for WallTemperature, HeatFlux, Convection, Radiation and face electrodes.
    Carved,
}

/// Which particles.
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum SelectorConfig {
    /// All particles.
    All,
    /// Particles touching a face (surface within half a radius of it).
    Face(FaceConfig),
    /// Particles whose centre lies in a region.
    Region(RegionConfig),
    /// Particles of a material.
    Material(String),
    /// Explicit ids.
    Particles(Vec<u32>),
}

/// Heat conduction.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalConfig {
    /// Initial temperature (°C) of every particle not fixed.
    #[serde(default)]
    pub initial_temperature: f64,
    /// Boundary conditions; faces without one are adiabatic.
    pub bcs: Vec<ThermalBcConfig>,
    /// Volumetric heat sources.
    #[serde(default)]
    pub sources: Vec<SourceConfig>,
    /// Time integration or steady state.
    pub solver: ThermalSolverConfig,
    /// Checkpoints of a transient, from which `demcon run --resume` continues a killed run.
    #[serde(default)]
    pub checkpoint: Option<CheckpointConfig>,
}

/// A thermal boundary condition.
#[derive(Debug, Clone, Deserialize, Serialize)]
pub enum ThermalBcConfig {
    /// Fixed temperature (°C) on the selected particles.
    FixedTemperature {
        /// Which particles.
        select: SelectorConfig,
        /// Temperature (°C).
        value: f64,
    },
    /// Temperature (°C) held on a container face itself (not on particles): each particle
    /// touching the face is linked to it by a half-contact λ S / h, h its centre-to-face
    /// distance and S its own transmission surface (C_t π R_p², or α(n_p) R_p²) — the bond to
    /// its mirror image across the face, cut in half. The boundary is then exactly at the
    /// face, where the papers put it, instead of a particle radius inside.
    WallTemperature {
        /// The face.
        face: FaceConfig,
        /// Temperature (°C): a number, or a time table `[(t, value), …]` (transients).
        value: TimedConfig,
    },
    /// Heat flux density (W/m², positive into the body) through a face, shared among the
    /// face's particles in proportion to their projected area.
    HeatFlux {
        /// The face.
        face: FaceConfig,
        /// Flux density (W/m²): a number, or a time table `[(t, value), …]` (transients).
        flux: TimedConfig,
    },
    /// Convection to a fluid at `t_inf` (°C): h (T_f − T∞) (W/m²) leaves through the face, T_f
    /// the face's own temperature. Each cell on the face (particle touching it, without
    /// cells) is linked to the fluid through its half-contact and the film h A in series —
    /// the finite-volume Robin condition, exact for a linear field. May share its face with a
    /// `Radiation`.
    Convection {
        /// The face.
        face: FaceConfig,
        /// Film coefficient h (W/(m²·K)), ≥ 0.
        h: f64,
        /// Fluid temperature T∞ (°C): a number, or a time table `[(t, value), …]` (transients).
        t_inf: TimedConfig,
    },
    /// Radiation to surroundings at `t_surroundings` (°C): ε σ (T_f⁴ − T_s⁴) (W/m², in
    /// kelvin) leaves through the face (a grey face seeing only the surroundings). A steady
    /// solve iterates to the exact law (Newton, `nonlinear_iterations` in `summary.json`); a
    /// transient lags the nonlinear part by one step. May share its face with a `Convection`.
    Radiation {
        /// The face.
        face: FaceConfig,
        /// Emissivity ε, in [0, 1].
        emissivity: f64,
        /// Surroundings' temperature T_s (°C): a number, or a time table `[(t, value), …]`
        /// (transients).
        t_surroundings: TimedConfig,
    },
}

/// A volumetric heat source.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SourceConfig {
    /// Which particles.
    pub select: SelectorConfig,
    /// Power density (W/m³ of material): a number, or a time table `[(t, value), …]`
    /// (transients).
    pub power_density: TimedConfig,
}

/// A value constant in time (`25.0`) or a time table (`[(0.0, 20.0), (60.0, 80.0)]`: points
/// (t (s), value), linear between them, a jump where two points share a time, held before the
/// first and after the last; in a transient the table must cover [0, t_end]).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum TimedConfig {
    /// The same value at every time.
    Constant(f64),
    /// Points (t (s), value).
    Table(Vec<(f64, f64)>),
}

impl Default for TimedConfig {
    fn default() -> Self {
        TimedConfig::Constant(0.0)
    }
}

impl From<f64> for TimedConfig {
    fn from(v: f64) -> Self {
        TimedConfig::Constant(v)
    }
}

/// Time step of the explicit solver.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
pub enum TimeStepConfig {
    /// `safety` × the exact positivity bound min_p C_p/Σ_q H_pq.
    Auto {
        /// Fraction of the bound, in (0, 1].
        safety: f64,
    },
    /// A fixed step (s); above the bound it is refused unless `allow_unstable`.
    Fixed {
        /// Step (s).
        dt: f64,
        /// Run even above the stability bound (blow-up is then detected and reported).
        #[serde(default)]
        allow_unstable: bool,
    },
    /// The heat paper's eq. 16 estimate (for comparison; usually unstable on polydisperse packings).
    Paper {
        /// Run even above the stability bound.
        #[serde(default)]
        allow_unstable: bool,
    },
}

/// Implicit scheme.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize)]
pub enum ImplicitSchemeConfig {
    /// First order, L-stable.
    #[default]
    BackwardEuler,
    /// Second order, A-stable.
    CrankNicolson,
}

/// Thermal solver.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
pub enum ThermalSolverConfig {
    /// Forward Euler (Haddad eq. 6).
    Explicit {
        /// End time (s).
        t_end: f64,
        /// Time step choice.
        dt: TimeStepConfig,
    },
    /// Implicit (one CG solve per step).
    Implicit {
        /// End time (s).
        t_end: f64,
        /// Step (s).
        dt: f64,
        /// Scheme.
        #[serde(default)]
        scheme: ImplicitSchemeConfig,
    },
    /// Steady state by one linear solve.
    Steady,
    /// Periodic homogenisation (a `Periodic` container, no boundary conditions or sources):
    /// three mean gradients on the periodic fluctuation give the full effective conductivity
    /// tensor, `etc_tensor` in `summary.json` (W/(m·K), row-major).
    Homogenize,
}

/// When a transient writes its checkpoint (`checkpoint: (every_steps: 1000, every_seconds:
/// 600.0)`): after every `every_steps` steps and/or once `every_seconds` of wall time have
/// passed since the last one, whichever comes first. Results never depend on it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointConfig {
    /// Steps between two checkpoints (≥ 1).
    #[serde(default)]
    pub every_steps: Option<u64>,
    /// Wall time between two checkpoints (s, > 0).
    #[serde(default)]
    pub every_seconds: Option<f64>,
}

/// Electric conduction.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ElectricConfig {
    /// Fixed potentials.
    pub electrodes: Vec<ElectrodeConfig>,
    /// Fraction η of the Joule power that heats the particles (in [0, 1]).
    #[serde(default = "default_eta")]
    pub eta: f64,
    /// Transmission-surface model of the electric network; `None` (the default): the thermal
    /// network's `surface`, so both physics share one network.
    #[serde(default)]
    pub surface: Option<SurfaceConfig>,
    /// Re-solve the potential when temperatures moved by more than this (K), for ρ_e(T).
    #[serde(default)]
    pub recouple_tolerance: Option<f64>,
    /// A current (A) imposed instead of a potential difference: it enters the body by
    /// `electrodes[0]` and leaves by `electrodes[1]` (exactly two); `electrodes[1]` keeps its
    /// potential, `electrodes[0]`'s is found by the solve (the one it gives is not used) and
    /// reported in `summary.json` (`electric.electrode_potentials`). With ρ_e(T) every re-solve
    /// keeps the current.
    #[serde(default)]
    pub current: Option<f64>,
    /// Periodic homogenisation instead of electrodes (`electrodes: []`, a `Periodic`
    /// container): the effective electric conductivity tensor, `conductivity_tensor` in
    /// `summary.json` (S/m, row-major).
    #[serde(default)]
    pub homogenize: bool,
}

fn default_eta() -> f64 {
    1.0
}

/// A fixed potential: either on particles (`select`: the selected particles are held at the
/// potential) or on a container face (`face`: the face itself is held at it and linked to
/// each particle touching it by a half-contact σ_p S_p / h_p, h_p the centre-to-face
/// distance). Give exactly one of the two.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ElectrodeConfig {
    /// Which particles are held at the potential.
    #[serde(default)]
    pub select: Option<SelectorConfig>,
    /// Which container face is held at the potential.
    #[serde(default)]
    pub face: Option<FaceConfig>,
    /// Potential (V): a number, or a time table `[(t, value), …]` in a transient (the
    /// potential is re-solved whenever the table changes it).
    pub potential: TimedConfig,
}

/// How a probe reads a field.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize)]
pub enum ProbeMethodConfig {
    /// The particle whose centre is nearest.
    #[default]
    Nearest,
    /// Average over the particles whose centre lies in a ball of this radius (m).
    Ball(f64),
}

/// Which particles a Halo averages over (`outputs.halo_phases`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
pub enum HaloPhasesConfig {
    /// Only the particles of the particle's own phase (the default: the tangential flux jumps
    /// across an interface, a Halo that mixes phases smears the jump).
    #[default]
    Same,
    /// Every particle in the ball (Haddad 2021 eqs. 22–23 as printed).
    All,
}

/// A probe point.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeConfig {
    /// Name (e.g. `A`).
    pub name: String,
    /// Point (m).
    pub point: (f64, f64, f64),
    /// Method.
    #[serde(default)]
    pub method: ProbeMethodConfig,
}

/// A profile along a segment.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileConfig {
    /// Name.
    pub name: String,
    /// Start (m).
    pub from: (f64, f64, f64),
    /// End (m).
    pub to: (f64, f64, f64),
    /// Number of points.
    pub points: usize,
    /// Method.
    #[serde(default)]
    pub method: ProbeMethodConfig,
}

/// Outputs.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputsConfig {
    /// Times (s) at which transient fields are recorded (probes, profiles, files).
    #[serde(default)]
    pub times: Vec<f64>,
    /// Also record at every breakpoint of the time tables (thermal values, electrode
    /// potentials) inside (0, t_end): the steps then land on them, so a jump or a kink of a
    /// table falls between two steps.
    #[serde(default)]
    pub times_at_breakpoints: bool,
    /// Probe points.
    #[serde(default)]
    pub probes: Vec<ProbeConfig>,
    /// Profiles.
    #[serde(default)]
    pub profiles: Vec<ProfileConfig>,
    /// Per-particle CSV of the final fields.
    #[serde(default)]
    pub particles_csv: bool,
    /// The particles' fields for ParaView: `particles.vtu` (steady), or for a transient the
    /// time series `particles.pvd` with one `particles_<k>.vtu` per output time and the end.
    #[serde(default = "yes")]
    pub vtk: bool,
    /// The contact network for ParaView: `contacts.vtp`, one line per contact and per wall
    /// link with its conductance, surface, length, flows and drops (a transient: the series
    /// `contacts.pvd` of `contacts_<k>.vtp`).
    #[serde(default)]
    pub contacts_vtk: bool,
    /// The Laguerre cells as polyhedra for ParaView: `cells.vtu` (with `surface: Laguerre`
    /// only; costs about 1 kB per particle on disk).
    #[serde(default)]
    pub cells_vtk: bool,
    /// Compute the per-particle heat flux (and write it).
    #[serde(default)]
    pub flux: bool,
    /// Halo smoothing ratio k of the flux (implies `flux`).
    #[serde(default)]
    pub halo: Option<f64>,
    /// Which particles each Halo averages over: `Same` (its own phase, the default) or `All`.
    /// Only with `halo`.
    #[serde(default)]
    pub halo_phases: Option<HaloPhasesConfig>,
    /// Effective conductivity along this axis from a steady run (fixed temperatures on its two faces).
    #[serde(default)]
    pub etc_axis: Option<AxisConfig>,
    /// PNG charts in `plots/` of the output folder: probes against time, profiles, and
    /// slices of the final fields (what `demcon plot` draws from the folder).
    #[serde(default)]
    pub plots: bool,
}

fn yes() -> bool {
    true
}

impl Default for OutputsConfig {
    fn default() -> Self {
        Self {
            times: Vec::new(),
            times_at_breakpoints: false,
            probes: Vec::new(),
            profiles: Vec::new(),
            particles_csv: false,
            vtk: true,
            contacts_vtk: false,
            cells_vtk: false,
            flux: false,
            halo: None,
            halo_phases: None,
            etc_axis: None,
            plots: false,
        }
    }
}
