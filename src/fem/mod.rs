//! Finite elements: quadrature, hex8, faces, kernels, sparse assembly, solvers.
//!
//! What is solved: the element integrals of transient heat conduction
//! (conductivity ∫λ∇N∇Nᵀ, capacity ∫ρcNNᵀ consistent or row-sum lumped,
//! convection faces ∫βNNᵀ and ∫βN) on trilinear hex8 volumes and bilinear
//! quad4 faces, assembled into a symmetric sparse matrix on a fixed pattern,
//! with Dirichlet rows/columns eliminated in place, and solved by faer's
//! sparse Cholesky with the symbolic analysis computed once per pattern.
//!
//! Pipeline, one file per step:
//! [`quadrature`] → [`hex8`] / [`quad4`] (shape functions, Jacobians) →
//! [`thermal_kernels`] (element matrices) → [`sparse`] (pattern, scatter
//! assembly, Dirichlet) → [`ordering`] (AMD, METIS nested dissection, or
//! geometric nested dissection) → [`solver`] (Cholesky, counters, residual)
//! → [`capacitance`] (a changed Dirichlet set solved on the old factor).
//!
//! How it is verified (`tests/it/fem_elements.rs`, `tests/it/fem_sparse.rs`):
//! Gauss rules against closed forms and polynomial exactness; hex8 partition
//! of unity, Kronecker property, gradients against central differences, exact
//! volumes of parallelepipeds, inverted elements rejected; conductivity
//! annihilates constants, is symmetric positive semi-definite and passes the
//! linear patch test on a distorted mesh; Σ lumped capacity = ρc·V; convection
//! matrices sum to β·area; sparse assembly equals dense assembly; Dirichlet
//! elimination equals the dense reduced solve; Cholesky residuals < 1e-12;
//! one symbolic analysis serves several numeric factorisations; the
//! orderings give the same solution; the capacitance correction equals a
//! fresh factorisation of the changed system to round-off.

pub mod capacitance;
pub mod elasticity;
pub mod error;
pub mod half_solves;
pub mod hex8;
pub mod hex8_modes;
pub mod ordering;
pub mod permuted_lower;
pub mod quad4;
pub mod quadrature;
pub mod solver;
pub mod sparse;
pub mod thermal_kernels;
pub mod two_cores;

pub use capacitance::{
    Capacitance, CapacitanceStats, Corrected, Coupling, Refine, RowChange, REFINE_TO,
};
pub use elasticity::{isotropic_d, poisson_matrix, principal_stresses, von_mises, SolidGauss};
pub use error::ElementError;
pub use half_solves::{ReachColumn, ReachWork};
pub use ordering::{
    metis_nested_dissection, metis_nested_dissection_with, nested_dissection, MetisError,
    MetisKnobs, Ordering,
};
pub use quadrature::{gauss_hex, gauss_legendre, gauss_quad, Rule};
pub use solver::{relative_residual, CholeskySolver, SolveError, SolverStats};
pub use sparse::{Pattern, PatternError, SparseSym, NO_DOF};
pub use thermal_kernels::{
    capacity_consistent, capacity_lumped, conductivity, element_volume_and_centroid,
    face_convection, face_convection_lumped, volume_load,
};
