//! Contact points of the ungrouted transverse joints.
//!
//! One point per pair of duplicated joint nodes (a on block j, b on block
//! j+1); its normal n points from A to B (area-weighted over the joint quads
//! around it) and its tributary area is a quarter of each adjacent quad.
//! Points where a joint touches rock share one node and carry no contact.
//! The gap of a point starts at the scene's initial gap when both of its
//! nodes first exist (the later block is cast against the earlier one).

use serde::{Deserialize, Serialize};

use crate::fem::quad4;
use crate::joint::{ContactError, ContactState, LocalFrame};
use crate::mesh::Mesh;

/// Geometry of one contact point.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPoint {
    pub joint: u32,
    pub zone: u32,
    pub a: u32,
    pub b: u32,
    pub frame: LocalFrame,
    /// tributary area [m²]
    pub area: f64,
}

/// Checkpointable state of one contact point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointPointState {
    /// both nodes exist
    pub paired: bool,
    /// normal gap (aperture) [m], ≥ 0 up to solver tolerance
    pub gap: f64,
    /// total contact force on side B in the local frame (t1, t2, n) [N]
    pub force: [f64; 3],
    pub state: PointState,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PointState {
    Open,
    Stick,
    Slip,
}

impl From<ContactState> for PointState {
    fn from(s: ContactState) -> Self {
        match s {
            ContactState::Open => PointState::Open,
            ContactState::Stick => PointState::Stick,
            ContactState::Slip => PointState::Slip,
        }
    }
}

/// The contact points of every joint of the mesh.
pub fn build_points(mesh: &Mesh) -> Result<Vec<JointPoint>, ContactError> {
    use std::collections::BTreeMap;
    // (a, b) → (joint, zone, Σ area-weighted normal, area)
    let mut acc: BTreeMap<(u32, u32), (u32, u32, [f64; 3], f64)> = BTreeMap::new();
    for pair in &mesh.face_pairs {
        let quad: [[f64; 3]; 4] = std::array::from_fn(|k| mesh.nodes[pair.nodes_a[k] as usize]);
        let area = quad4::area(&quad);
        let n = quad4::normal_scaled(&quad, [0.0, 0.0]);
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            .sqrt()
            .max(f64::MIN_POSITIVE);
        for k in 0..4 {
            let (a, b) = (pair.nodes_a[k], pair.nodes_b[k]);
            if a == b {
                continue;
            }
            let e = acc
                .entry((a, b))
                .or_insert((pair.joint, pair.zone, [0.0; 3], 0.0));
            for d in 0..3 {
                e.2[d] += 0.25 * area * n[d] / norm;
            }
            e.3 += 0.25 * area;
        }
    }
    acc.into_iter()
        .map(|((a, b), (joint, zone, n, area))| {
            Ok(JointPoint {
                joint,
                zone,
                a,
                b,
                frame: LocalFrame::from_normal(n)?,
                area,
            })
        })
        .collect()
}
