//! Errors raised by element geometry (hex8 Jacobians, quad4 faces).

use thiserror::Error;

/// A geometric defect found while evaluating an element at a point.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum ElementError {
    /// det(∂x/∂ξ) ≤ 0 (or not finite) at a reference point: the hex is
    /// inverted, degenerate or its nodes are not in VTK order.
    #[error("hex8 Jacobian determinant {det:e} is not positive at reference point {point:?}")]
    NonPositiveJacobian { det: f64, point: [f64; 3] },
    /// |∂x/∂s × ∂x/∂t| = 0 (or not finite) at a reference point of a quad face.
    #[error(
        "quad4 face area element {area_element:e} is not positive at reference point {point:?}"
    )]
    DegenerateFace { area_element: f64, point: [f64; 2] },
}
