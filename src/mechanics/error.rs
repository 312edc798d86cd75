//! The errors of the mechanical model.

use crate::fem::{ElementError, SolveError};
use crate::material::AgeStepError;

use super::contact_step::JointStepError;
use super::live::LiveError;

/// Relative residual above which a mechanical solve is rejected.
pub(super) const RESIDUAL_TOLERANCE: f64 = 1e-8;

#[derive(Debug, thiserror::Error)]
pub enum MechError {
    #[error("mechanical solve on day {day:.3}: {source}")]
    Solve { day: f64, source: SolveError },
    #[error("mechanical solve on day {day:.3}: relative residual {residual:.3e} exceeds {RESIDUAL_TOLERANCE:.0e}")]
    Residual { day: f64, residual: f64 },
    #[error("element {element}: {source}")]
    Element {
        element: usize,
        source: ElementError,
    },
    #[error("element {element} on day {day:.3}: {source}")]
    Age {
        element: usize,
        day: f64,
        source: AgeStepError,
    },
    #[error("the mesh has rock elements but the mechanical settings have no rock (the scene's [rock] table)")]
    NoRock,
    #[error("mechanical settings: {0}")]
    Settings(#[from] crate::vocab::Invalid),
    #[error("joint contact on day {day:.3}: {source}")]
    Contact {
        day: f64,
        source: crate::joint::ContactError,
    },
    #[error("prescribed displacement on node {node} component {comp}: the dof is not supported, or is on side b of a joint, or is tied to its rock grid line (solver.rock_coarsening)")]
    NotSupported { node: u32, comp: u8 },
    #[error("condensing the rock: {0}")]
    Condensation(SolveError),
    #[error("joints on day {day:.3}: {source}")]
    Joints { day: f64, source: JointStepError },
    #[error("mechanical unknowns on day {day:.3}: {source}")]
    Live { day: f64, source: LiveError },
    #[error(transparent)]
    Supports(#[from] super::supports::SupportError),
}

impl MechError {
    /// The unknown (in the live system's numbering) whose pivot failed.
    pub fn pivot_dof(&self) -> Option<usize> {
        match self {
            MechError::Solve { source, .. } => source.pivot_dof(),
            MechError::Joints {
                source: JointStepError::Solve(e),
                ..
            } => e.pivot_dof(),
            MechError::Live {
                source: LiveError::Solve(e),
                ..
            } => e.pivot_dof(),
            _ => None,
        }
    }
}
