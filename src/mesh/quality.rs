//! Element quality of a hex8 mesh, for `groutready mesh`'s summary: the
//! smallest Jacobian determinant over every element corner and the worst
//! edge aspect ratio.
//!
//! * [`min_jacobian`]: det J of the trilinear map at the 8 reference
//!   corners (ξ, η, ζ = ±1) of each element, [`crate::fem::hex8::jacobian`].
//!   The trilinear map's det J is not linear, but its corner values decide
//!   inversion in practice and are what `Mesh::validate` checks; for an
//!   axis-aligned box of sides a, b, c it is abc/8 everywhere.
//! * [`worst_aspect`]: longest over shortest of each element's 12 edges.
//!
//! Both take plain nodes and hexahedra so that they apply to a generated
//! [`super::Mesh`] and to an imported [`super::import::RawMesh`] alike.
//! Verified by the unit tests: a unit cube (det = 1/8 at every corner,
//! aspect 1), a 50 × 1 × 1 box (aspect 50), a squashed corner found with its
//! element and corner.

use crate::fem::hex8;

/// The 12 edges of a hex8 (VTK corner order).
const EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Where a quality measure is worst.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Worst {
    pub value: f64,
    /// Element index (0-based).
    pub element: usize,
    /// Corner 0..8 (for the Jacobian; 0 for the aspect ratio).
    pub corner: usize,
}

fn coords(nodes: &[[f64; 3]], hex: &[u32; 8]) -> [[f64; 3]; 8] {
    std::array::from_fn(|k| nodes[hex[k] as usize])
}

/// The smallest Jacobian determinant \[m³\] over all element corners, with
/// its element and corner; `None` without elements.
pub fn min_jacobian(nodes: &[[f64; 3]], hexes: &[[u32; 8]]) -> Option<Worst> {
    let mut worst: Option<Worst> = None;
    for (e, h) in hexes.iter().enumerate() {
        let x = coords(nodes, h);
        for (corner, xi) in hex8::NODES.iter().enumerate() {
            let det = hex8::jacobian(&x, *xi).1;
            // NaN (a degenerate map) counts as worst of all
            if worst.is_none_or(|w| det.is_nan() || det < w.value) {
                worst = Some(Worst {
                    value: det,
                    element: e,
                    corner,
                });
            }
        }
    }
    worst
}

/// The largest ratio of longest to shortest edge of an element, with the
/// element; `None` without elements (a zero-length edge gives infinity).
pub fn worst_aspect(nodes: &[[f64; 3]], hexes: &[[u32; 8]]) -> Option<Worst> {
    let mut worst: Option<Worst> = None;
    for (e, h) in hexes.iter().enumerate() {
        let x = coords(nodes, h);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for [a, b] in EDGES {
            let l = (0..3)
                .map(|k| (x[a][k] - x[b][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            lo = lo.min(l);
            hi = hi.max(l);
        }
        let ratio = if lo > 0.0 { hi / lo } else { f64::INFINITY };
        if worst.is_none_or(|w| ratio > w.value) {
            worst = Some(Worst {
                value: ratio,
                element: e,
                corner: 0,
            });
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned box of sides a × b × c with corners in VTK order.
    fn block(a: f64, b: f64, c: f64) -> (Vec<[f64; 3]>, Vec<[u32; 8]>) {
        let nodes = hex8::NODES
            .iter()
            .map(|r| {
                [
                    (r[0] + 1.0) / 2.0 * a,
                    (r[1] + 1.0) / 2.0 * b,
                    (r[2] + 1.0) / 2.0 * c,
                ]
            })
            .collect();
        (nodes, vec![[0, 1, 2, 3, 4, 5, 6, 7]])
    }

    #[test]
    fn unit_cube_has_det_one_eighth_and_aspect_one() {
        let (nodes, hexes) = block(1.0, 1.0, 1.0);
        for (corner, xi) in hex8::NODES.iter().enumerate() {
            let det = hex8::jacobian(&coords(&nodes, &hexes[0]), *xi).1;
            assert!((det - 0.125).abs() < 1e-15, "corner {corner}: {det}");
        }
        let w = min_jacobian(&nodes, &hexes).unwrap();
        assert!((w.value - 0.125).abs() < 1e-15);
        assert_eq!(worst_aspect(&nodes, &hexes).unwrap().value, 1.0);
    }

    #[test]
    fn long_box_has_aspect_fifty() {
        let (nodes, hexes) = block(50.0, 1.0, 1.0);
        let w = worst_aspect(&nodes, &hexes).unwrap();
        assert_eq!(w.value, 50.0);
        let j = min_jacobian(&nodes, &hexes).unwrap();
        assert!((j.value - 50.0 / 8.0).abs() < 1e-13, "{}", j.value);
    }

    #[test]
    fn the_worst_element_and_corner_are_found() {
        // Two unit cubes side by side; the second has corner 6 pushed in
        // along the diagonal, which shrinks det J at that corner only.
        let (mut nodes, mut hexes) = block(1.0, 1.0, 1.0);
        let shift = nodes.len() as u32;
        nodes.extend(
            block(1.0, 1.0, 1.0)
                .0
                .iter()
                .map(|p| [p[0] + 2.0, p[1], p[2]]),
        );
        hexes.push(std::array::from_fn(|k| k as u32 + shift));
        let c6 = &mut nodes[shift as usize + 6];
        *c6 = [c6[0] - 0.2, c6[1] - 0.2, c6[2] - 0.2];
        let w = min_jacobian(&nodes, &hexes).unwrap();
        assert_eq!((w.element, w.corner), (1, 6));
        // At corner 6, ∂x/∂ξ = (x6 − x7)/2, ∂x/∂η = (x6 − x5)/2, ∂x/∂ζ =
        // (x6 − x2)/2: 0.8 on their own axis, −0.2 on the others.
        let m: [[f64; 3]; 3] = [[0.8, -0.2, -0.2], [-0.2, 0.8, -0.2], [-0.2, -0.2, 0.8]];
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        assert!((det - 0.4).abs() < 1e-15);
        assert!(
            (w.value - det / 8.0).abs() < 1e-14,
            "{} vs {}",
            w.value,
            det / 8.0
        );
        assert_eq!(worst_aspect(&nodes, &hexes).unwrap().element, 1);
    }
}
